//! `engine bench`: the frame of every method at the same views, interleaved
//! in one process so machine noise hits all alike — the bare one-texture
//! pass, the static EM, the default PEM frame (deferred compositing of the
//! blended samples) and its variants, and the papers' multipass. Views sit
//! half-way between samples so every blend is drawn; maps are resident.
//! The last two rows then run, each alone, with the eye one sample further
//! every frame, so each frame needs a new sample's maps decoded (ahead, on
//! the worker): decoding on against resident maps, in one run — the last
//! decoding straight into the slots frames sample (lavapipe), the one
//! before it through staging buffers and an upload pass (what a GPU does).
//! "default, edge filter" adds the film filter along the reflectors'
//! outlines (`--edge-filter`). "default, bilinear views" blends a view
//! between rings from its grid cell's four corners instead of the
//! triangle of three that holds it.
//! Each row also reports the compositing passes' fragment-shader
//! invocations per covered reflector pixel (the overdraw the deferred
//! design removes). PEM variants light the room as `--room` says (inferred
//! light maps by default); "default, analytic room" is the default frame
//! with the analytic room, so the two room passes are timed side by side.
//! "rem" is reflection-space IBR (its source maps traced first when
//! missing), lit like the PEM variants. A scene with a glass object is
//! benched as glass ([`glass`]).

mod glass;
mod report;

use report::rows;
pub use report::{BenchKind, BenchReport, BenchRow, RoomPass, room_pass};

use crate::options::{PemOptions, RunPlace};
use crate::pem::player::{Compositing, PemKind, PemSettings};
use crate::perf::{PassReport, PerfLog, PerfReport};
use crate::play::{Session, compile_context};
use crate::renderer::{FrameMode, Renderer};
use crate::util::stats::median;
use anyhow::Result;
use inference::scene::ViewBlend;
use std::time::Instant;

/// How a variant draws.
#[derive(Clone, Copy)]
enum Draws {
    Bare,
    StaticEm,
    Pem(PemSettings),
    /// Reflection-space IBR (`--rem-size`, `--rem-level` as given).
    Rem,
}

/// The variants, in table order; the last [`MOVING`] move (decoding on).
fn variants() -> Vec<(&'static str, Draws)> {
    let default = PemSettings::new(PemKind::Layered);
    let multipass = PemSettings {
        compositing: Compositing::Multipass,
        ..default
    };
    vec![
        ("bare", Draws::Bare),
        ("static-em", Draws::StaticEm),
        ("default", Draws::Pem(default)),
        (
            "default, edge filter",
            Draws::Pem(PemSettings {
                edge_filter: true,
                ..default
            }),
        ),
        (
            "default, nearest sample",
            Draws::Pem(PemSettings {
                blend: false,
                ..default
            }),
        ),
        (
            "default, bilinear views",
            Draws::Pem(PemSettings {
                view_blend: ViewBlend::Bilinear,
                ..default
            }),
        ),
        (
            "default, distant only",
            Draws::Pem(PemSettings {
                local_layer: false,
                ..default
            }),
        ),
        ("default, analytic room", Draws::Pem(default)),
        ("multipass", Draws::Pem(multipass)),
        ("rem", Draws::Rem),
        (
            "default, decoding, staging uploads",
            Draws::Pem(PemSettings {
                staging_uploads: true,
                ..default
            }),
        ),
        ("default, decoding", Draws::Pem(default)),
    ]
}

/// The last variants, which move one sample a frame (each alone, in
/// turn); the others draw resident maps.
const MOVING: usize = 2;

/// How long to measure, and where the maps come from.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Timed frames per view and variant.
    pub frames_per_view: u32,
    /// Untimed frames first at each view.
    pub warmup: u32,
    pub pem: PemOptions,
    /// The views' elevation above the orbit plane, degrees [default: half
    /// way to the first ring above it, so four samples blend; 0 on a 1D
    /// orbit].
    pub elevation_deg: Option<f32>,
}

pub fn bench(place: &RunPlace, opts: &BenchOptions) -> Result<BenchReport> {
    let Session {
        scene,
        out,
        device,
        renderer,
        ..
    } = Session::open(place)?;
    let ctx = compile_context(place, &scene, &out);
    let elevation = opts
        .elevation_deg
        .unwrap_or_else(|| between_rings(&scene.orbit));
    if scene.objects.iter().any(|o| o.glass.is_some()) {
        let mut report = glass::bench(&ctx, &device, opts, renderer, elevation)?;
        write(&out, &mut report)?;
        return Ok(report);
    }
    // Before any compiling: the variants draw reflectors' maps.
    if !scene.objects.iter().any(|o| o.em.is_some()) {
        anyhow::bail!(
            "{}: nothing to bench: no reflective object has [objects.em] settings and no object is glass",
            scene.origin
        );
    }
    let (width, height) = place.size;
    let variants = variants();
    let (mut renderers, which) = renderers_for(&ctx, &device, opts, &variants, renderer)?;
    let views = 8u32;
    let per_view = opts.frames_per_view.max(1);
    let mut logs: Vec<PerfLog> = variants.iter().map(|_| PerfLog::default()).collect();
    let progress = indicatif::ProgressBar::new(u64::from((1 + MOVING as u32) * views * per_view));
    let run = Run {
        orbit: &scene.orbit,
        elevation,
        variants: &variants,
        which: &which,
        views,
        per_view,
        warmup: opts.warmup,
        progress: &progress,
    };
    let covered = run.resident(&mut renderers, &mut logs)?;
    let moving_covered = run.moving(&mut renderers, &mut logs)?;
    progress.finish_and_clear();
    let reports: Vec<PerfReport> = logs
        .into_iter()
        .zip(&variants)
        .map(|(log, (name, _))| log.report(&device.name, &scene.name, name, [width, height], &[]))
        .collect();
    let rows = rows(reports, covered, (MOVING, moving_covered));
    let passes: Vec<(&str, &[PassReport])> = rows
        .iter()
        .map(|r| (r.name.as_str(), &r.report.passes[..]))
        .collect();
    let room_pass = room_pass(&passes);
    let mut report = BenchReport {
        kind: BenchKind::Reflectors,
        views,
        elevation_deg: elevation,
        frames_per_view: per_view,
        covered_pixels: Some(covered as u64),
        moving_covered_pixels: Some(moving_covered as u64),
        rows,
        room_pass,
        written: Vec::new(),
    };
    write(&out, &mut report)?;
    Ok(report)
}

/// `bench.json`, and `bench.png`: where each row's frame goes.
fn write(out: &std::path::Path, report: &mut BenchReport) -> Result<()> {
    let (json, png) = (out.join("bench.json"), out.join("bench.png"));
    crate::util::files::write_json(&json, &*report)?;
    crate::eval::bars::stacked_bars(&png, &report.chart())?;
    report.written = vec![json, png];
    Ok(())
}

/// One renderer per PEM variant (switching settings re-creates slots),
/// the first shared by the raster variants; which renderer each variant
/// draws with.
fn renderers_for(
    ctx: &crate::compile::CompileContext,
    device: &crate::backend::Device,
    opts: &BenchOptions,
    variants: &[(&'static str, Draws)],
    first: Renderer,
) -> Result<(Vec<Renderer>, Vec<usize>)> {
    let scene = ctx.scene;
    let (width, height) = ctx.size;
    let mut renderers = vec![first];
    let mut which = Vec::new();
    let room = match opts.pem.room {
        crate::options::RoomShading::Inferred => Some(crate::compile::room::room_maps(ctx)?),
        crate::options::RoomShading::Analytic => None,
    };
    for (name, draws) in variants {
        match draws {
            Draws::Bare | Draws::StaticEm => which.push(0),
            Draws::Pem(settings) => {
                let mut r = Renderer::new(device, scene, width, height)?;
                let source = crate::compile::map_source(ctx, &opts.pem, &settings.layers())?;
                r.set_pem(scene, *settings, source)?;
                if *name != "default, analytic room" {
                    r.set_room(scene, room.as_ref())?;
                }
                which.push(renderers.len());
                renderers.push(r);
            }
            Draws::Rem => {
                let mut r = Renderer::new(device, scene, width, height)?;
                let settings = crate::rem::sources::RemSettings {
                    size: opts.pem.rem_size,
                    level: opts.pem.rem_level,
                    ..Default::default()
                };
                let maps = crate::rem::sources::source_maps(scene, ctx.out, settings)?;
                r.set_rem(scene, &maps, opts.pem.blend)?;
                r.set_room(scene, room.as_ref())?;
                which.push(renderers.len());
                renderers.push(r);
            }
        }
    }
    Ok((renderers, which))
}

/// The measuring loop's fixed inputs.
struct Run<'a> {
    orbit: &'a inference::scene::Orbit,
    /// The views' elevation, degrees.
    elevation: f32,
    variants: &'a [(&'static str, Draws)],
    which: &'a [usize],
    views: u32,
    per_view: u32,
    warmup: u32,
    progress: &'a indicatif::ProgressBar,
}

/// With elevation rings, views sit between rings too: four samples blend.
fn between_rings(orbit: &inference::scene::Orbit) -> f32 {
    if orbit.rings > 1 {
        0.5 * orbit.ring_elevation(1)
    } else {
        0.0
    }
}

impl Run<'_> {
    /// Every variant but the moving ones, interleaved view by view with the
    /// maps resident; returns the median covered reflector pixels.
    fn resident(&self, renderers: &mut [Renderer], logs: &mut [PerfLog]) -> Result<f64> {
        let o = &self.orbit;
        let moving = self.variants.len() - MOVING;
        let mut covered = Vec::new();
        let view_eye = |v: u32| {
            let k =
                ((v as f32 + 0.5) / self.views as f32 * o.samples.saturating_sub(1) as f32) as u32;
            o.eye(o.between_deg(k, 0.5), self.elevation)
        };
        let frames = self.warmup + self.per_view;
        for v in 0..self.views {
            let eye = view_eye(v);
            for i in 0..frames {
                // Frames in flight, as in playback: each renderer's next
                // frame is this view again. Not the next view's first
                // (a warm-up frame): announced, its maps would be decoded
                // ahead behind this view's last timed frame.
                if i == self.warmup {
                    // Decoding ahead, started by the new view, must not run
                    // behind the timed frames.
                    renderers.iter_mut().for_each(Renderer::settle);
                    covered.push(renderers[self.which[2]].covered_pixels()? as f64);
                }
                for (index, (_, draws)) in self.variants.iter().enumerate().take(moving) {
                    let start = Instant::now();
                    let r = &mut renderers[self.which[index]];
                    r.set_next_view(eye, o.view(eye));
                    let stats = r.frame(mode(draws), eye, o.view(eye))?;
                    if i >= self.warmup {
                        let ms = start.elapsed().as_secs_f64() * 1e3;
                        logs[index].record(ms, &stats.passes, stats.cpu);
                    }
                }
                if i >= self.warmup {
                    self.progress.inc(1);
                }
            }
        }
        Ok(median(&covered))
    }

    /// The moving variants, each alone in turn: one sample further every
    /// frame, its maps decoded ahead while the previous frame draws;
    /// returns the median covered reflector pixels at the timed views.
    fn moving(&self, renderers: &mut [Renderer], logs: &mut [PerfLog]) -> Result<f64> {
        let o = &self.orbit;
        let last = o.samples.saturating_sub(1).max(1);
        let eye_of = |i: u32| o.eye(o.between_deg(i % last, 0.5), self.elevation);
        let mut eyes = Vec::new();
        let first = self.variants.len() - MOVING;
        for index in first..self.variants.len() {
            let r = &mut renderers[self.which[index]];
            eyes.clear();
            for i in 0..self.warmup + self.views * self.per_view {
                let eye = eye_of(i);
                let start = Instant::now();
                r.set_next_view(eye_of(i + 1), o.view(eye_of(i + 1)));
                let stats = r.frame(FrameMode::Pem, eye, o.view(eye))?;
                if i >= self.warmup {
                    let ms = start.elapsed().as_secs_f64() * 1e3;
                    logs[index].record(ms, &stats.passes, stats.cpu);
                    eyes.push(eye);
                    self.progress.inc(1);
                }
            }
            // Its worker must not decode behind the next variant's frames.
            r.settle();
            logs[index].add_ahead_decodes(r.drain_ahead_decode_ms());
        }
        // Counted after the timed frames, so the read-backs do not give
        // the decoding worker time the timed frames would not have had.
        let r = &mut renderers[self.which[self.variants.len() - 1]];
        let mut covered = Vec::with_capacity(eyes.len());
        for eye in eyes {
            r.frame(FrameMode::Pem, eye, o.view(eye))?;
            covered.push(r.covered_pixels()? as f64);
        }
        Ok(median(&covered))
    }
}

/// How a variant's frames are drawn.
fn mode(d: &Draws) -> FrameMode {
    match d {
        Draws::Bare => FrameMode::Bare,
        Draws::StaticEm => FrameMode::StaticEm,
        Draws::Pem(_) => FrameMode::Pem,
        Draws::Rem => FrameMode::Rem,
    }
}
