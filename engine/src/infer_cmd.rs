//! `engine infer`: layered environment maps by least squares for orbit
//! samples. Per sample: the traced layers (traced first when missing or
//! stale), then for each reflector with `[objects.em]` and each of its
//! layers — distant on the room's box, local on the reflector's
//! minimum-volume ellipsoid (premultiplied RGBA) — probe renders on this
//! device, the regularized solve warm-started from the previous sample, the
//! forward-mapping baseline, and the maps written as EXR with a report.

use crate::backend::{DeviceOptions, create_device};
use crate::cli::InferArgs;
use crate::play::prepare_output;
use crate::probe::VulkanProbe;
use anyhow::{Context, Result, bail};
use glam::Vec3;
use inference::em_geometry::{EmGeometry, bounding_ellipsoid, texgen};
use inference::infer::maps::{read_map, write_map};
use inference::infer::{LayerResult, Target, infer_layer};
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::{EmLayer, Material, Object, Scene};
use inference::solve::SolveOptions;
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::trace::{TraceSettings, Tracer, cache, camera, output};
use serde::Serialize;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

#[derive(Serialize)]
pub struct LayerReport {
    pub name: String,
    pub psnr_db: PsnrPair,
    pub rows: usize,
    pub nnz: usize,
    pub rows_across_cube_faces: usize,
    pub probe_renders: u32,
    pub a_vs_render_psnr_db: f64,
    pub cg_iterations: Vec<u32>,
    pub probe_s: f64,
    pub assembly_s: f64,
    pub solve_s: f64,
    pub diagnostics: Vec<String>,
}

#[derive(Serialize)]
pub struct PsnrPair {
    pub least_squares: f64,
    pub forward_mapping: f64,
}

#[derive(Serialize)]
pub struct SampleReport {
    pub sample: u32,
    pub probe_renders: u32,
    /// The worst layer's `A x` against an actual render of random content.
    pub a_vs_render_psnr_db: f64,
    pub solve_s: f64,
    pub warm_started: bool,
    pub layers: Vec<LayerReport>,
}

/// A JSON number for PSNRs, which are ∞ for exact matches.
fn finite_or_max(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::MAX.copysign(v)
    }
}

impl From<&LayerResult> for LayerReport {
    fn from(r: &LayerResult) -> Self {
        Self {
            name: r.name.clone(),
            psnr_db: PsnrPair {
                least_squares: finite_or_max(r.psnr_least_squares_db),
                forward_mapping: finite_or_max(r.psnr_forward_db),
            },
            rows: r.rows,
            nnz: r.nnz,
            rows_across_cube_faces: r.rows_across_faces,
            probe_renders: r.probe_renders,
            a_vs_render_psnr_db: finite_or_max(r.a_vs_render_psnr_db),
            cg_iterations: r.iterations.clone(),
            probe_s: r.probe_time.as_secs_f64(),
            assembly_s: r.assembly_time.as_secs_f64(),
            solve_s: r.solve_time.as_secs_f64(),
            diagnostics: r.diagnostics.clone(),
        }
    }
}

/// target | least squares | forward mapping, cropped to the object's
/// bounding box (RGB, premultiplied for RGBA layers), sRGB PNG.
fn write_comparison(path: &Path, width: u32, target: &[[f32; 4]], r: &LayerResult) -> Result<()> {
    let (Some(x0), Some(x1)) = (
        r.pixels.iter().map(|p| p % width).min(),
        r.pixels.iter().map(|p| p % width).max(),
    ) else {
        return Ok(()); // nothing visible, nothing to show
    };
    let (y0, y1) = (r.pixels[0] / width, r.pixels[r.pixels.len() - 1] / width);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let gap = 4;
    let total = 3 * w + 2 * gap;
    let mut out = vec![[0.0f32; 4]; (total * h) as usize];
    let object: std::collections::HashSet<u32> = r.pixels.iter().copied().collect();
    for (panel, image) in [target, &r.rendered_least_squares, &r.rendered_forward]
        .into_iter()
        .enumerate()
    {
        for y in 0..h {
            for x in 0..w {
                let p = (y0 + y) * width + x0 + x;
                if object.contains(&p) {
                    out[(y * total + panel as u32 * (w + gap) + x) as usize] = image[p as usize];
                }
            }
        }
    }
    crate::capture::write_png(path, total, h, &out)?;
    Ok(())
}

fn output_dir(args: &InferArgs, scene: &Scene) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("infer"))
}

/// What a job infers.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// An EM layer on its geometry, indexed by texgen.
    Em(EmLayer, EmGeometry),
    /// A parameterized texture map: the reflector's whole appearance as a
    /// 2D texture on its own texture coordinates.
    Ptm,
}

/// One map of one reflector to infer.
struct Job<'a> {
    object: &'a Object,
    kind: Kind,
    origin: Vec3,
    resolution: u32,
}

impl Job<'_> {
    fn name(&self) -> String {
        let layer = match self.kind {
            Kind::Em(EmLayer::Distant, _) => "specular_distant",
            Kind::Em(EmLayer::Local, _) => "specular_local",
            Kind::Ptm => "ptm",
        };
        format!("{}.{layer}", self.object.name)
    }
    fn channels(&self) -> usize {
        match self.kind {
            Kind::Em(EmLayer::Local, _) => 4,
            _ => 3,
        }
    }
    fn shape(&self) -> TextureShape {
        match self.kind {
            Kind::Em(..) => TextureShape::Cube {
                size: self.resolution,
            },
            Kind::Ptm => TextureShape::Tex2D {
                width: self.resolution,
                height: self.resolution,
            },
        }
    }
}

/// The EM layers the scene asks for: reflective objects with EM settings.
fn jobs<'a>(scene: &'a Scene, em_size: Option<u32>) -> Result<Vec<Job<'a>>> {
    let (room_min, room_max) = scene.bounds();
    let mut jobs = Vec::new();
    for object in &scene.objects {
        let reflective = matches!(
            scene.materials.get(object.material),
            Some(Material::Mirror { .. } | Material::Glossy { .. })
        );
        let Some(em) = object.em.as_ref().filter(|_| reflective) else {
            continue;
        };
        let resolution = em_size.unwrap_or(em.resolution);
        if resolution == 0 || !resolution.is_power_of_two() || resolution > 2048 {
            bail!(
                "--em-size / {}: EM resolution {resolution} (expected a power of two up to 2048)",
                object.name
            );
        }
        let origin = object.mesh.area_weighted_centroid();
        for &layer in &em.layers {
            let geometry = match layer {
                EmLayer::Distant => EmGeometry::Box {
                    min: room_min,
                    max: room_max,
                },
                EmLayer::Local => EmGeometry::Ellipsoid {
                    center: origin,
                    radii: bounding_ellipsoid(origin, &object.mesh.positions),
                },
            };
            jobs.push(Job {
                object,
                kind: Kind::Em(layer, geometry),
                origin,
                resolution,
            });
        }
        jobs.push(Job {
            object,
            kind: Kind::Ptm,
            origin,
            resolution,
        });
    }
    Ok(jobs)
}

/// The traced layers of sample `k`, tracing them first when missing or
/// traced with other inputs.
fn traced_layers(
    trace_dir: &Path,
    scene: &Scene,
    tracer: &Tracer,
    k: u32,
    settings: &TraceSettings,
) -> Result<(Vec<output::ExrLayer>, u64)> {
    let stem = trace_dir.join(format!("sample_{k:04}"));
    let eye = tracer.sample_eye(k)?;
    let key = cache::key(scene, eye, settings);
    if !cache::is_fresh(&stem, key) {
        if let Some(dir) = stem.parent() {
            prepare_output(dir)?;
        }
        let image = tracer.render(eye, settings)?;
        output::write_image(&stem, &image)
            .with_context(|| format!("writing {}", stem.display()))?;
        cache::record(&stem, key)?;
    }
    let path = output::with_suffix(&stem, ".exr");
    Ok((output::read_exr(&path)?, key))
}

/// `name`'s pixels as RGBA (premultiplied by A when `premultiply`).
fn target_pixels(
    layers: &[output::ExrLayer],
    name: &str,
    premultiply: bool,
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>> {
    let (_, channels) = layers
        .iter()
        .find(|(n, _)| n == name)
        .with_context(|| format!("traced image has no layer {name:?}"))?;
    let get = |c: &str| channels.iter().find(|(n, _)| n == c).map(|(_, v)| v);
    let (Some(r), Some(g), Some(b)) = (get("R"), get("G"), get("B")) else {
        bail!("layer {name:?}: expected channels R, G, B");
    };
    if r.len() != pixel_count {
        bail!(
            "layer {name:?}: {} pixels, the probe renders have {pixel_count} (trace at the same --size)",
            r.len()
        );
    }
    let a = get("A");
    Ok((0..pixel_count)
        .map(|i| {
            let alpha = a.map_or(1.0, |a| a[i]);
            let k = if premultiply { alpha } else { 1.0 };
            [r[i] * k, g[i] * k, b[i] * k, alpha]
        })
        .collect())
}

/// The reflector's own appearance from its layers, as the runtime
/// composites it: `fresnel × (local over distant)` (+ diffuse if any).
fn composite_pixels(
    layers: &[output::ExrLayer],
    object: &str,
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>> {
    let fresnel = target_pixels(layers, &format!("{object}.fresnel"), false, pixel_count)?;
    let distant = target_pixels(
        layers,
        &format!("{object}.specular_distant"),
        false,
        pixel_count,
    )?;
    let local = target_pixels(
        layers,
        &format!("{object}.specular_local"),
        true,
        pixel_count,
    )
    .ok();
    let diffuse = target_pixels(layers, &format!("{object}.diffuse"), false, pixel_count).ok();
    Ok((0..pixel_count)
        .map(|i| {
            let (f, d) = (fresnel[i], distant[i]);
            let l = local.as_ref().map_or([0.0; 4], |l| l[i]);
            let base = diffuse.as_ref().map_or([0.0; 4], |v| v[i]);
            let c = |k: usize| base[k] + f[k] * (l[k] + (1.0 - l[3]) * d[k]);
            [c(0), c(1), c(2), 1.0]
        })
        .collect())
}

fn inputs_key(trace_key: u64, job: &Job, options: &SolveOptions, size: (u32, u32)) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (trace_key, job.name(), job.resolution, size).hash(&mut h);
    format!(
        "{:?} {:?} {:?} {:?}",
        job.kind, job.origin, options.eps_f, options.eps_b
    )
    .hash(&mut h);
    // The reflector's mesh decides texgen.
    for p in &job.object.mesh.positions {
        p.to_array().map(f32::to_bits).hash(&mut h);
    }
    h.finish()
}

#[derive(Serialize)]
pub struct DiffuseReport {
    pub object: String,
    pub views: Vec<u32>,
    pub rows: usize,
    pub probe_renders: u32,
    pub psnr_per_view_db: Vec<f64>,
    pub cg_iterations: Vec<u32>,
    pub solve_s: f64,
}

/// Texture coordinates that give every surface point its own texel, which
/// a view-independent texture needs (tiled UVs would force one tile to hold
/// the lighting of the whole surface). A flat object is projected onto its
/// plane, normalised to [0, 1]²; otherwise its own UVs are kept.
fn unique_uvs(mesh: &inference::scene::Mesh) -> Vec<glam::Vec2> {
    let (lo, hi) = mesh.bounds();
    let size = hi - lo;
    let flat = size.min_element() <= 1e-4 * size.max_element();
    if !flat {
        return mesh.uvs.clone();
    }
    let thin = if size.x <= size.y.min(size.z) {
        0
    } else if size.y <= size.z {
        1
    } else {
        2
    };
    let (u, v) = [(1, 2), (0, 2), (0, 1)][thin];
    mesh.positions
        .iter()
        .map(|p| glam::Vec2::new((p[u] - lo[u]) / size[u], (p[v] - lo[v]) / size[v]))
        .collect()
}

/// `--diffuse OBJECT`: one texture for all `--views`, stacked.
fn infer_diffuse(args: &InferArgs, object_name: &str) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let object = scene.object(object_name).with_context(|| {
        format!(
            "--diffuse {object_name}: no such object in {}",
            scene.source.display()
        )
    })?;
    if !matches!(
        scene.materials.get(object.material),
        Some(Material::Diffuse { .. })
    ) {
        bail!(
            "--diffuse {object_name}: the object's material is not diffuse (expected a Lambertian object)"
        );
    }
    let size = args.texture_size;
    if size == 0 || !size.is_power_of_two() || size > 4096 {
        bail!("--texture-size {size}: expected a power of two up to 4096");
    }
    if let Some(&k) = args.views.iter().find(|&&k| k >= scene.orbit.samples) {
        bail!(
            "--views: sample {k} out of range 0..{} (the scene's orbit.samples)",
            scene.orbit.samples
        );
    }
    let tracer = Tracer::new(&scene)?;
    let (width, height) = args.size;
    let settings = TraceSettings {
        width,
        height,
        spp: args.spp.unwrap_or(inference::trace::DEFAULT_SPP),
        progress: true,
        ..TraceSettings::default()
    };
    settings.validate()?;
    let out = output_dir(args, &scene);
    prepare_output(&out)?;
    let trace_dir = args
        .trace_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("trace"));
    let device = create_device(&DeviceOptions {
        device_name: args.device.clone(),
        validate: args.validate,
    })?;
    let mut probe = VulkanProbe::new(&device)?;
    let projection = camera::projection(&scene, width, height);
    let layer = format!("{object_name}.diffuse");
    let uvs = unique_uvs(&object.mesh);
    let mut targets = Vec::new();
    for &k in &args.views {
        let (layers, _) = traced_layers(&trace_dir, &scene, &tracer, k, &settings)?;
        targets.push(target_pixels(
            &layers,
            &layer,
            false,
            width as usize * height as usize,
        )?);
    }
    let views: Vec<(ProbeGeometry, Target)> = args
        .views
        .iter()
        .zip(&targets)
        .map(|(&k, pixels)| -> Result<_> {
            let eye = tracer.sample_eye(k)?;
            Ok((
                ProbeGeometry {
                    key: u64::from(k) + 1,
                    positions: object.mesh.positions.clone(),
                    indices: object.mesh.indices.clone(),
                    lookup: Lookup::Uv(uvs.clone()),
                    view_proj: projection * scene.orbit.view(eye),
                    width,
                    height,
                },
                Target {
                    name: &layer,
                    pixels,
                    channels: 3,
                },
            ))
        })
        .collect::<Result<_>>()?;
    let options = SolveOptions {
        eps_f: args.eps_f,
        ..SolveOptions::default()
    };
    let shape = TextureShape::Tex2D {
        width: size,
        height: size,
    };
    let result = inference::infer::stacked::infer_stacked(&mut probe, &views, shape, &options)
        .with_context(|| format!("stacked solve for {layer}"))?;
    write_map(
        &out.join(format!("{layer}.exr")),
        &result.layout,
        &result.map,
    )?;
    let report = DiffuseReport {
        object: object_name.into(),
        views: args.views.clone(),
        rows: result.rows,
        probe_renders: result.probe_renders,
        psnr_per_view_db: result
            .psnr_per_view_db
            .iter()
            .map(|&v| finite_or_max(v))
            .collect(),
        cg_iterations: result.iterations.clone(),
        solve_s: result.solve_time.as_secs_f64(),
    };
    std::fs::write(
        out.join("diffuse_report.json"),
        serde_json::to_string_pretty(&report)?,
    )?;
    Ok(format!(
        "{layer}: {} views stacked, {} rows, {} probe renders, PSNR per view {:?} dB, solve {:.2} s ({:?} CG it.)\n",
        args.views.len(),
        report.rows,
        report.probe_renders,
        report
            .psnr_per_view_db
            .iter()
            .map(|v| (v * 100.0).round() / 100.0)
            .collect::<Vec<_>>(),
        report.solve_s,
        report.cg_iterations
    ))
}

pub fn infer(args: &InferArgs) -> Result<String> {
    if let Some(object) = &args.diffuse {
        return infer_diffuse(args, object);
    }
    let scene = Scene::load(&args.scene)?;
    let tracer = Tracer::new(&scene)?;
    let (width, height) = args.size;
    let settings = TraceSettings {
        width,
        height,
        spp: args.spp.unwrap_or(inference::trace::DEFAULT_SPP),
        progress: true,
        ..TraceSettings::default()
    };
    settings.validate()?;
    let samples: Vec<u32> = match args.sample {
        Some(k) if k >= scene.orbit.samples => {
            bail!(
                "--sample {k}: out of range 0..{} (the scene's orbit.samples)",
                scene.orbit.samples
            )
        }
        Some(k) => vec![k],
        None => (0..scene.orbit.samples).collect(),
    };
    let jobs = jobs(&scene, args.em_size)?;
    if jobs.is_empty() {
        bail!(
            "{}: no reflective object has [objects.em] settings: nothing to infer",
            scene.source.display()
        );
    }
    let out = output_dir(args, &scene);
    prepare_output(&out)?;
    let trace_dir = args
        .trace_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("trace"));
    let device = create_device(&DeviceOptions {
        device_name: args.device.clone(),
        validate: args.validate,
    })?;
    let mut probe = VulkanProbe::new(&device)?;
    let options = SolveOptions {
        eps_f: args.eps_f,
        ..SolveOptions::default()
    };
    let projection = camera::projection(&scene, width, height);
    let pixel_count = width as usize * height as usize;
    let bar = indicatif::ProgressBar::new(samples.len() as u64 * jobs.len() as u64);
    let mut reports = Vec::new();
    let mut skipped = 0;
    for &k in &samples {
        let (layers, trace_key) = traced_layers(&trace_dir, &scene, &tracer, k, &settings)?;
        let eye = tracer.sample_eye(k)?;
        let dir = out.join(format!("sample_{k:04}"));
        prepare_output(&dir)?;
        let mut report = SampleReport {
            sample: k,
            probe_renders: 0,
            a_vs_render_psnr_db: f64::MAX,
            solve_s: 0.0,
            warm_started: false,
            layers: Vec::new(),
        };
        for job in &jobs {
            let name = job.name();
            let key = inputs_key(trace_key, job, &options, args.size);
            let key_path = dir.join(format!("{name}.key"));
            let map_path = dir.join(format!("{name}.exr"));
            if args.all
                && map_path.is_file()
                && std::fs::read_to_string(&key_path).ok() == Some(key.to_string())
            {
                skipped += 1;
                bar.inc(1);
                continue;
            }
            let mesh = &job.object.mesh;
            let (pixels, lookup) = match job.kind {
                Kind::Em(layer, em_geometry) => {
                    let mut lookups = vec![[0.0f32; 4]; mesh.positions.len()];
                    texgen(
                        &em_geometry,
                        job.origin,
                        eye,
                        &mesh.positions,
                        &mesh.normals,
                        &mut lookups,
                    );
                    (
                        target_pixels(&layers, &name, layer == EmLayer::Local, pixel_count)?,
                        Lookup::Cube(
                            lookups
                                .iter()
                                .map(|l| Vec3::new(l[0], l[1], l[2]))
                                .collect(),
                        ),
                    )
                }
                Kind::Ptm => (
                    composite_pixels(&layers, &job.object.name, pixel_count)?,
                    Lookup::Uv(mesh.uvs.clone()),
                ),
            };
            let geometry = ProbeGeometry {
                key: key ^ u64::from(k),
                positions: mesh.positions.clone(),
                indices: mesh.indices.clone(),
                lookup,
                view_proj: projection * scene.orbit.view(eye),
                width,
                height,
            };
            let shape = job.shape();
            let layout = TextureLayout::full_chain(shape);
            let previous = k
                .checked_sub(1)
                .map(|p| {
                    out.join(format!("sample_{p:04}"))
                        .join(format!("{name}.exr"))
                })
                .filter(|p| p.is_file())
                .and_then(|p| read_map(&p, &layout, job.channels()).ok());
            report.warm_started |= previous.is_some();
            bar.set_message(format!("sample {k} {name}"));
            let target = Target {
                name: &name,
                pixels: &pixels,
                channels: job.channels(),
            };
            let result = infer_layer(
                &mut probe,
                &geometry,
                shape,
                &target,
                previous.as_deref(),
                &options,
                &mut |_, _| {},
            )
            .with_context(|| format!("sample {k}, {name}"))?;
            write_map(&map_path, &layout, &result.map)?;
            write_comparison(&dir.join(format!("{name}.png")), width, &pixels, &result)?;
            std::fs::write(&key_path, key.to_string())
                .with_context(|| format!("writing {}", key_path.display()))?;
            report.probe_renders += result.probe_renders;
            report.a_vs_render_psnr_db = report
                .a_vs_render_psnr_db
                .min(finite_or_max(result.a_vs_render_psnr_db));
            report.solve_s += result.solve_time.as_secs_f64();
            report.layers.push(LayerReport::from(&result));
            bar.inc(1);
        }
        if !report.layers.is_empty() {
            let json = serde_json::to_string_pretty(&report)?;
            std::fs::write(dir.join("report.json"), &json)?;
            reports.push(report);
        }
    }
    bar.finish_and_clear();
    let mut text = String::new();
    for r in &reports {
        for l in &r.layers {
            text += &format!(
                "sample {:>3} {:<26} LS {:>6.2} dB  forward {:>6.2} dB  A·x vs render {:>6.1} dB  {} rows  {} renders  probe {:.1} s  assembly {:.1} s  solve {:.2} s ({:?} CG it.)\n",
                r.sample,
                l.name,
                l.psnr_db.least_squares,
                l.psnr_db.forward_mapping,
                l.a_vs_render_psnr_db,
                l.rows,
                l.probe_renders,
                l.probe_s,
                l.assembly_s,
                l.solve_s,
                l.cg_iterations
            );
        }
    }
    if skipped > 0 {
        text += &format!("{skipped} layers already inferred from the same inputs: skipped\n");
    }
    // A single sample's report is also DIR/report.json, as tools expect.
    if let [only] = reports.as_slice() {
        std::fs::write(out.join("report.json"), serde_json::to_string_pretty(only)?)?;
    } else if !reports.is_empty() {
        std::fs::write(
            out.join("report.json"),
            serde_json::to_string_pretty(&reports)?,
        )?;
    }
    Ok(text)
}
