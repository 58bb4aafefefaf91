//! `engine bench`: the frame of every method at the same views, interleaved
//! in one process so machine noise hits all alike — the bare one-texture
//! pass, the static EM, the default PEM frame (deferred compositing of the
//! blended samples) and its variants, and the papers' multipass. Views sit
//! half-way between samples so every blend is drawn; maps are resident.
//! The last row then runs alone with its eye one sample further every
//! frame, so each frame needs a new sample's maps decoded (ahead, on the
//! worker) and uploaded: decoding on against resident maps, in one run.
//! Each row also reports the compositing passes' fragment-shader
//! invocations per covered reflector pixel (the overdraw the deferred
//! design removes). PEM variants light the room as `--room` says (inferred
//! light maps by default); "default, analytic room" is the default frame
//! with the analytic room, so the two room passes are timed side by side.
//! "rem" is reflection-space IBR (its source maps traced first when
//! missing), lit like the PEM variants.

use crate::options::{PemOptions, RunPlace};
use crate::pem::player::{Compositing, PemKind, PemSettings};
use crate::perf::{PassReport, PerfLog, PerfReport};
use crate::play::{Session, compile_context};
use crate::renderer::{FrameMode, Renderer};
use crate::util::stats::median;
use anyhow::Result;
use serde::Serialize;
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

/// The variants, in table order; the last one moves (decoding on).
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
            "default, nearest sample",
            Draws::Pem(PemSettings {
                blend: false,
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
        ("default, decoding", Draws::Pem(default)),
    ]
}

/// Passes whose fragment invocations count as compositing the reflectors.
const COMPOSITING: [&str; 3] = ["pem_composite", "pem", "pem_blend"];

#[derive(Serialize)]
pub struct BenchRow {
    pub name: String,
    pub frame_ms_median: f64,
    pub fps: f64,
    pub submit_to_fence_ms_median: f64,
    pub texgen_ms_median: f64,
    /// Median frame over the bare frame's median.
    pub ratio_to_bare: f64,
    /// Median frame over the static-EM frame's median.
    pub ratio_to_static_em: f64,
    /// Fragment-shader invocations of the compositing passes (`pem_composite`,
    /// or `pem` + `pem_blend` multipass) per covered reflector pixel.
    pub compositing_invocations_per_pixel: Option<f64>,
    pub report: PerfReport,
}

#[derive(Serialize)]
pub struct BenchReport {
    pub views: u32,
    /// The views' elevation above the orbit plane, degrees.
    pub elevation_deg: f32,
    pub frames_per_view: u32,
    /// Reflector pixels covered at the views (median over the views).
    pub covered_pixels: u64,
    /// The same at the last row's views (it moves along the samples).
    pub moving_covered_pixels: u64,
    pub rows: Vec<BenchRow>,
    /// The inferred room pass against the analytic one, from the default
    /// rows with each room (the whole-frame issue's cost goal).
    pub room_pass: Option<RoomPass>,
}

/// One run's room passes, median GPU times.
#[derive(Serialize, Debug, PartialEq)]
pub struct RoomPass {
    pub inferred_ms: f64,
    pub analytic_ms: f64,
    /// Inferred over analytic.
    pub ratio: f64,
}

/// The `room` pass of the rows named `default` and `default, analytic
/// room`, when both ran it.
pub fn room_pass(rows: &[(&str, &[PassReport])]) -> Option<RoomPass> {
    let room = |name: &str| {
        let (_, passes) = rows.iter().find(|(n, _)| *n == name)?;
        let p = passes.iter().find(|p| p.name == "room")?;
        Some(p.gpu_ms_median)
    };
    let (inferred_ms, analytic_ms) = (room("default")?, room("default, analytic room")?);
    (analytic_ms > 0.0).then(|| RoomPass {
        inferred_ms,
        analytic_ms,
        ratio: inferred_ms / analytic_ms,
    })
}

impl BenchReport {
    pub fn table(&self) -> String {
        let mut out = format!(
            "{} views between samples at {:+.1}° x {} frames; maps resident but in the last row; {} reflector pixels\n{:<28} {:>9} {:>7} {:>9} {:>8} {:>7} {:>9} {:>10}\n",
            self.views,
            self.elevation_deg,
            self.frames_per_view,
            self.covered_pixels,
            "variant",
            "frame ms",
            "fps",
            "GPU ms",
            "texgen",
            "x bare",
            "x static",
            "inv./pixel"
        );
        for r in &self.rows {
            out += &format!(
                "{:<28} {:>9.2} {:>7.1} {:>9.2} {:>8.3} {:>7.2} {:>9.2} {:>10}\n",
                r.name,
                r.frame_ms_median,
                r.fps,
                r.submit_to_fence_ms_median,
                r.texgen_ms_median,
                r.ratio_to_bare,
                r.ratio_to_static_em,
                r.compositing_invocations_per_pixel
                    .map_or("-".into(), |v| format!("{v:.2}"))
            );
        }
        if let Some(r) = &self.room_pass {
            out += &format!(
                "room pass: inferred {:.2} ms, analytic {:.2} ms ({:.3}x the analytic)\n",
                r.inferred_ms, r.analytic_ms, r.ratio
            );
        }
        out
    }
}

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
    let (width, height) = place.size;
    let variants = variants();
    let (mut renderers, which) = renderers_for(&ctx, &device, opts, &variants, renderer)?;
    let views = 8u32;
    let per_view = opts.frames_per_view.max(1);
    let mut logs: Vec<PerfLog> = variants.iter().map(|_| PerfLog::default()).collect();
    let progress = indicatif::ProgressBar::new(u64::from(2 * views * per_view));
    let elevation = opts
        .elevation_deg
        .unwrap_or_else(|| between_rings(&scene.orbit));
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
    let rows = rows(reports, covered, moving_covered);
    let passes: Vec<(&str, &[PassReport])> = rows
        .iter()
        .map(|r| (r.name.as_str(), &r.report.passes[..]))
        .collect();
    let room_pass = room_pass(&passes);
    let report = BenchReport {
        views,
        elevation_deg: elevation,
        frames_per_view: per_view,
        covered_pixels: covered as u64,
        moving_covered_pixels: moving_covered as u64,
        rows,
        room_pass,
    };
    crate::util::files::write_json(&out.join("bench.json"), &report)?;
    Ok(report)
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
    /// Every variant but the last, interleaved view by view with the maps
    /// resident; returns the median covered reflector pixels.
    fn resident(&self, renderers: &mut [Renderer], logs: &mut [PerfLog]) -> Result<f64> {
        let o = &self.orbit;
        let moving = self.variants.len() - 1;
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
                // frame is this view again, or the next view's first.
                let next = if i + 1 < frames { eye } else { view_eye(v + 1) };
                if i == self.warmup {
                    // Decoding ahead, started by the new view, must not run
                    // behind the timed frames.
                    renderers.iter_mut().for_each(Renderer::settle);
                    covered.push(renderers[self.which[2]].covered_pixels()? as f64);
                }
                for (index, (_, draws)) in self.variants.iter().enumerate().take(moving) {
                    let start = Instant::now();
                    let r = &mut renderers[self.which[index]];
                    r.set_next_view(next, o.view(next));
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

    /// The last variant alone: one sample further every frame, its maps
    /// decoded ahead while the previous frame draws; returns the median
    /// covered reflector pixels at its timed frames' views.
    fn moving(&self, renderers: &mut [Renderer], logs: &mut [PerfLog]) -> Result<f64> {
        let o = &self.orbit;
        let moving = self.variants.len() - 1;
        let last = o.samples.saturating_sub(1).max(1);
        let mut eyes = Vec::new();
        let eye_of = |i: u32| o.eye(o.between_deg(i % last, 0.5), self.elevation);
        for i in 0..self.warmup + self.views * self.per_view {
            let eye = eye_of(i);
            let start = Instant::now();
            let r = &mut renderers[self.which[moving]];
            r.set_next_view(eye_of(i + 1), o.view(eye_of(i + 1)));
            let stats = r.frame(FrameMode::Pem, eye, o.view(eye))?;
            if i >= self.warmup {
                let ms = start.elapsed().as_secs_f64() * 1e3;
                logs[moving].record(ms, &stats.passes, stats.cpu);
                eyes.push(eye);
                self.progress.inc(1);
            }
        }
        // Counted after the timed frames, so the read-backs do not give
        // the decoding worker time the timed frames would not have had.
        let r = &mut renderers[self.which[moving]];
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

/// The table's rows: ratios to the bare and static-EM frames (rows 0, 1),
/// compositing invocations per covered pixel (the last row's at its own
/// views).
fn rows(reports: Vec<PerfReport>, covered: f64, moving_covered: f64) -> Vec<BenchRow> {
    let bare_ms = reports[0].frame_ms_median;
    let static_ms = reports[1].frame_ms_median;
    let last = reports.len().saturating_sub(1);
    reports
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            let covered = if i == last { moving_covered } else { covered };
            let invocations: u64 = r
                .passes
                .iter()
                .filter(|p| COMPOSITING.contains(&p.name.as_str()))
                .map(|p| p.fragment_invocations)
                .sum();
            BenchRow {
                name: r.mode.clone(),
                frame_ms_median: r.frame_ms_median,
                fps: 1e3 / r.frame_ms_median,
                submit_to_fence_ms_median: r.cpu.submit_to_fence_ms_median,
                texgen_ms_median: r.cpu.texgen_ms_median,
                ratio_to_bare: r.frame_ms_median / bare_ms,
                ratio_to_static_em: r.frame_ms_median / static_ms,
                compositing_invocations_per_pixel: (invocations > 0 && covered > 0.0)
                    .then(|| invocations as f64 / covered),
                report: r,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(name: &str, ms: f64) -> PassReport {
        PassReport {
            name: name.into(),
            gpu_ms_median: ms,
            gpu_ms_max: ms,
            fragment_invocations: 0,
        }
    }

    #[test]
    fn the_room_pass_compares_the_two_default_rows() {
        let inferred = [pass("pem_gbuffer", 7.0), pass("room", 9.0)];
        let analytic = [pass("room", 10.0), pass("pem_composite", 9.0)];
        let other = [pass("room", 1.0)];
        let rows: Vec<(&str, &[PassReport])> = vec![
            ("static-em", &other),
            ("default, analytic room", &analytic),
            ("default", &inferred),
        ];
        assert_eq!(
            room_pass(&rows),
            Some(RoomPass {
                inferred_ms: 9.0,
                analytic_ms: 10.0,
                ratio: 0.9
            })
        );
        // A missing row or pass, or a zero analytic time: nothing to compare.
        assert_eq!(room_pass(&rows[..2]), None);
        let no_room = [pass("bare", 3.0)];
        assert_eq!(
            room_pass(&[("default", &inferred), ("default, analytic room", &no_room)]),
            None
        );
        let zero = [pass("room", 0.0)];
        assert_eq!(
            room_pass(&[("default", &inferred), ("default, analytic room", &zero)]),
            None
        );
    }
}
