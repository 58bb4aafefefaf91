//! Infers the glass scene's room shell map from traced views (thesis
//! §6.3.3) instead of tracing it from the shell's origin, and writes it
//! where playback reads the traced one, so `engine eval --scene glass
//! --data COPY` scores the inferred map.
//!
//! Per view: the lens tessellated to τ, each vertex's two exit-ray lookups
//! into the room shell, the tracer's per-term targets (the radiance along
//! the greedy paths' exit rays) with their confidence; probe renders give
//! each term's rendering matrix, and one regularized solve fits the map to
//! both terms of every view at once, each row weighted by √confidence.
//!
//! `cargo run --release -p engine --example glass_shell_infer -- DATA_DIR
//!  [--azimuths 0,25,50,75] [--elevations 0] [--spp 16] [--tau 5] [--warm]
//!  [--r-weight W] [--refine λ] [--write-traced]`
//!
//! `--warm` starts the solve from the traced map, `--r-weight` scales the
//! reflection term's rows against the refraction term's, `--refine λ`
//! solves for a correction to the traced map (targets less its render,
//! prior λ‖δ‖²), `--write-traced` writes the traced map instead (a check
//! of the file path).
//! (DATA_DIR holds `glass/room_shell.bin`, traced when missing; it is
//! overwritten with the inferred map under the same key.)

use engine::compile::glass_shells::solve as frame;

use std::path::PathBuf;
use std::time::Instant;

use engine::backend::{DeviceOptions, create_device};
use engine::probe::VulkanProbe;
use glam::Vec3;
use half::f16;
use inference::glass::targets::trace_targets;
use inference::glass::vertices::{Term, term_lookups};
use inference::glass::{Lens, Screen, ShellSet, TessSettings, tessellate};
use inference::infer::{MatrixCache, Target, View, Views, infer_layer_with};
use inference::probe::{Lookup, ProbeGeometry, ProbeRenderer};
use inference::scene::Scene;
use inference::solve::SolveOptions;
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::trace::{TraceSettings, Tracer};

struct Args {
    data: PathBuf,
    azimuths: Vec<f32>,
    elevations: Vec<f32>,
    spp: u32,
    tau: f32,
    warm: bool,
    r_weight: f32,
    write_traced: bool,
    refine: Option<f32>,
    frame: bool,
}

fn list(s: &str) -> Result<Vec<f32>, std::num::ParseFloatError> {
    s.split(',').map(|v| v.trim().parse()).collect()
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let mut it = std::env::args().skip(1);
    let mut a = Args {
        data: PathBuf::from(
            it.next()
                .ok_or("usage: glass_shell_infer DATA_DIR [options]")?,
        ),
        azimuths: vec![0.0, 25.0, 50.0, 75.0],
        elevations: vec![0.0],
        spp: 16,
        tau: 5.0,
        warm: false,
        r_weight: 1.0,
        write_traced: false,
        refine: None,
        frame: false,
    };
    while let Some(flag) = it.next() {
        let mut v = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--azimuths" => a.azimuths = list(&v()?)?,
            "--elevations" => a.elevations = list(&v()?)?,
            "--spp" => a.spp = v()?.parse()?,
            "--tau" => a.tau = v()?.parse()?,
            "--warm" => a.warm = true,
            "--r-weight" => a.r_weight = v()?.parse()?,
            "--write-traced" => a.write_traced = true,
            "--refine" => a.refine = Some(v()?.parse()?),
            "--frame" => a.frame = true,
            other => return Err(format!("unknown option {other}").into()),
        }
    }
    Ok(a)
}

/// One term of one view: what the probe renders draw and what they fit.
struct TermView {
    term: Term,
    geometry: ProbeGeometry,
    pixels: Vec<[f32; 4]>,
    weights: Vec<f32>,
}

/// The scene's glass object and its room shell.
struct Glass {
    scene: Scene,
    object: usize,
    lens: Lens,
    origin: Vec3,
    size: u32,
    shells: ShellSet,
}

impl Glass {
    fn load() -> Result<Self, Box<dyn std::error::Error>> {
        let scene = Scene::load("glass")?;
        let object = scene
            .objects
            .iter()
            .position(|o| o.glass.is_some())
            .ok_or("the scene has no glass object")?;
        let o = &scene.objects[object];
        let size = o.glass.as_ref().map_or(256, |g| g.resolution);
        let lens = Lens::new(&scene, &o.name)?;
        let origin = o.mesh.area_weighted_centroid();
        let shells =
            inference::glass::room_shell(&scene, origin, inference::glass::room_box_shape(&scene));
        Ok(Self {
            scene,
            object,
            lens,
            origin,
            size,
            shells,
        })
    }
}

const SIZE: (u32, u32) = (640, 480);

/// Both terms of every view `args` names: tessellation, lookups, targets;
/// with `--frame`, each view's frame too.
type Traced = (Vec<TermView>, Vec<frame::FrameView>);

fn term_views(g: &Glass, args: &Args) -> Result<Traced, Box<dyn std::error::Error>> {
    let tracer = Tracer::new(&g.scene)?;
    let (width, height) = SIZE;
    let projection = inference::trace::camera::projection(&g.scene, width, height);
    let settings = TraceSettings {
        width,
        height,
        spp: args.spp,
        ..TraceSettings::default()
    };
    let mut terms = Vec::new();
    let mut frames = Vec::new();
    // Probe renders keep a mesh by key: one per term of every view.
    let mut next_key = 0u64;
    for &el in &args.elevations {
        for &az in &args.azimuths {
            let start = Instant::now();
            let eye: Vec3 = g.scene.orbit.eye(az, el);
            let view_proj = projection * g.scene.orbit.view(eye);
            let screen = Screen {
                view_proj,
                width,
                height,
            };
            let tess = tessellate(&g.lens, eye, screen, TessSettings::new(args.tau));
            let targets = trace_targets(&tracer, &g.lens, &g.shells, eye, &settings);
            let first = terms.len();
            for (term, images) in [(Term::T, &targets.t), (Term::R, &targets.r)] {
                next_key += 1;
                let key = next_key * 0x9e37_79b9_7f4a_7c15;
                let lookup = Lookup::Cube {
                    dirs: term_lookups(&tess, &g.shells, term, 0),
                    lod_bias: 0.0,
                };
                let weights = images.confidence.iter().map(|c| c.max(0.0).sqrt());
                terms.push(TermView {
                    term,
                    geometry: ProbeGeometry {
                        key,
                        positions: tess.positions.clone(),
                        indices: tess.indices.clone(),
                        lookup,
                        view_proj,
                        width,
                        height,
                    },
                    pixels: images.shells[0].clone(),
                    weights: weights.collect(),
                });
            }
            if args.frame {
                // An independent trace of the whole frame (another seed than
                // the eval's references).
                let beauty = tracer.render(
                    eye,
                    &TraceSettings {
                        seed: 1,
                        ..settings
                    },
                )?;
                let rgb = beauty.layer("beauty").ok_or("no beauty layer")?;
                // The frame solve uses the two terms' geometry, not their
                // per-term targets.
                let mut pair = terms.split_off(first).into_iter().map(|t| t.geometry);
                let (Some(t), Some(r)) = (pair.next(), pair.next()) else {
                    return Err("a view without its two terms".into());
                };
                frames.push(frame::FrameView {
                    t,
                    r,
                    targets,
                    beauty: rgb
                        .pixels
                        .chunks_exact(3)
                        .map(|p| [p[0], p[1], p[2]])
                        .collect(),
                });
            }
            eprintln!(
                "view az {az} el {el}: {} vertices, targets traced, {:.1} s",
                tess.positions.len(),
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok((terms, frames))
}

/// Each target less the traced map's render: what a correction must fit.
fn subtract_render(
    probe: &mut VulkanProbe,
    terms: &mut [TermView],
    layout: &TextureLayout,
    traced: &[[f32; 4]],
) -> Result<(), Box<dyn std::error::Error>> {
    for t in terms {
        let image = probe.render(&t.geometry, layout, traced)?;
        for (px, r) in t.pixels.iter_mut().zip(&image) {
            for c in 0..3 {
                px[c] -= r[c];
            }
        }
    }
    Ok(())
}

/// The map's channels as f16 RGBA texels, negative values clamped.
fn shell_halves(map: &[Vec<f32>], len: usize) -> Vec<f16> {
    (0..len)
        .flat_map(|i| {
            let c = |k: usize| f16::from_f32(map[k][i].max(0.0));
            [c(0), c(1), c(2), f16::ONE]
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = parse()?;
    let g = Glass::load()?;
    let traced = engine::glass::shell::room_shell_bytes(
        &g.scene,
        &args.data,
        g.object as u32,
        g.origin,
        g.size,
    )?;
    let (mut terms, frames) = term_views(&g, &args)?;
    let device = create_device(&DeviceOptions::default())?;
    let mut probe = VulkanProbe::new(&device)?;
    let shape = TextureShape::Cube { size: g.size };
    let layout = TextureLayout::full_chain(shape);
    let warm: Vec<Vec<f32>> = {
        let halves: &[f16] = bytemuck::cast_slice(&traced);
        (0..3)
            .map(|c| halves.chunks_exact(4).map(|t| t[c].to_f32()).collect())
            .collect()
    };
    if args.frame {
        let (map, stats) = frame::solve_frames(&mut probe, &frames, shape, &warm, args.refine)?;
        for (c, s) in stats.iter().enumerate() {
            eprintln!(
                "channel {c}: {} rows, {} CG iterations, relative residual {:.2e}",
                s.rows, s.iterations, s.relative_residual
            );
        }
        return write_map(&g, &args, &map, &layout);
    }
    let traced_texels = inference::infer::layer::texels(&warm, layout.len());
    if args.refine.is_some() {
        subtract_render(&mut probe, &mut terms, &layout, &traced_texels)?;
    }
    let views: Vec<View> = terms
        .iter()
        .enumerate()
        .map(|(i, t)| View {
            id: i as u64,
            geometry: &t.geometry,
            target: Target {
                name: "glass.room_shell",
                pixels: &t.pixels,
                channels: 3,
            },
            weight: if t.term == Term::R {
                args.r_weight
            } else {
                1.0
            },
            pixel_weights: Some(&t.weights),
        })
        .collect();
    let (own, neighbours) = views.split_first().ok_or("no views")?;
    let start = Instant::now();
    let result = infer_layer_with(
        &mut probe,
        Views {
            own: *own,
            neighbours,
            cache: &mut MatrixCache::new(terms.len()),
        },
        shape,
        args.warm.then_some(warm.as_slice()),
        &SolveOptions {
            eps_prior: args.refine.unwrap_or(0.0),
            ..SolveOptions::default()
        },
        &mut |_, _| {},
    )?;
    eprintln!(
        "solved {} rows in {:.1} s (probes {:.1} s, solve {:.1} s); own view: least squares {:.2} dB, forward {:.2} dB",
        result.rows,
        start.elapsed().as_secs_f64(),
        result.probe_time.as_secs_f64(),
        result.solve_time.as_secs_f64(),
        result.psnr_least_squares_db,
        result.psnr_forward_db
    );
    // The traced map against the same target through the same renders: is
    // the fit limited by the targets or by the solve?
    let own_image = probe.render(own.geometry, &layout, &traced_texels)?;
    eprintln!(
        "own view: the traced map renders {:.2} dB against the same target",
        inference::infer::layer::psnr_over_rows(&own_image, &own.target, &result.pixels)
    );
    if result.layout != layout {
        return Err("the solve's layout is not the shell map's".into());
    }
    // --write-traced: the traced map through the same writer (a check that
    // the eval then scores exactly the traced map); --refine: traced + δ.
    let map: Vec<Vec<f32>> = match (args.write_traced, args.refine) {
        (true, _) => warm,
        (false, Some(_)) => (0..3)
            .map(|c| {
                warm[c]
                    .iter()
                    .zip(&result.map[c])
                    .map(|(t, d)| t + d)
                    .collect()
            })
            .collect(),
        (false, None) => result.map,
    };
    write_map(&g, &args, &map, &layout)
}

/// Writes `map` where playback reads the traced shell map, under its key.
fn write_map(
    g: &Glass,
    args: &Args,
    map: &[Vec<f32>],
    layout: &TextureLayout,
) -> Result<(), Box<dyn std::error::Error>> {
    let file = engine::glass::shell::shell_path(&args.data);
    let halves = shell_halves(map, layout.len());
    inference::files::write_bytes(&file, bytemuck::cast_slice(&halves))?;
    let key = engine::glass::shell::shell_key(&g.scene, g.object as u32, g.origin, g.size);
    inference::key::write_record(&file, &key)?;
    eprintln!("wrote the shell map to {}", file.display());
    Ok(())
}
