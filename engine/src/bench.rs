//! `engine bench`: the frame of every method at the same views, interleaved
//! in one process so machine noise hits all alike — the bare one-texture
//! pass, the static EM, and layered PEMs built up one pass at a time
//! (distant layer of the nearest sample; + local layer; + the blend pass to
//! the second sample). Views sit half-way between samples so the blend pass
//! always runs; maps are resident. The last variant then runs alone with
//! its eye one sample further every frame, so each frame needs a new
//! sample's maps decoded (ahead, on the worker) and uploaded: decoding on
//! against textures already resident, in one run.
//! Differences of medians give the per-pass split that lavapipe's
//! timestamps cannot (it attributes most work to a frame's first pass).

use crate::options::{PemOptions, RunPlace};
use crate::pem::player::{PemKind, PemSettings};
use crate::perf::{PerfLog, PerfReport};
use crate::play::{Session, compile_context};
use crate::renderer::{FrameMode, Renderer};
use anyhow::Result;
use serde::Serialize;
use std::time::Instant;

/// The variants, in table order: name, PEM set-up (None = no PEM).
const VARIANTS: [(&str, Option<(bool, bool)>); 6] = [
    ("bare", None),
    ("static-em", None),
    ("pem distant, nearest sample", Some((false, false))),
    ("pem layered, nearest sample", Some((true, false))),
    ("pem layered, blended", Some((true, true))),
    ("pem layered, blended, decoding", Some((true, true))),
];
/// The variant whose eye moves one sample per frame.
const MOVING: usize = 5;

#[derive(Serialize)]
pub struct BenchRow {
    pub name: String,
    pub frame_ms_median: f64,
    pub submit_to_fence_ms_median: f64,
    pub texgen_ms_median: f64,
    /// Median frame over the static-EM frame's median.
    pub ratio_to_static_em: f64,
    pub report: PerfReport,
}

#[derive(Serialize)]
pub struct BenchReport {
    pub views: u32,
    pub frames_per_view: u32,
    pub rows: Vec<BenchRow>,
    /// Per-pass split from differences of medians (ms).
    pub split_ms: Vec<(String, f64)>,
}

impl BenchReport {
    pub fn table(&self) -> String {
        let mut out = format!(
            "{} views between samples x {} frames; maps resident but in the last row\n{:<32} {:>9} {:>9} {:>8} {:>9}\n",
            self.views, self.frames_per_view, "variant", "frame ms", "GPU ms", "texgen", "x static"
        );
        for r in &self.rows {
            out += &format!(
                "{:<32} {:>9.2} {:>9.2} {:>8.3} {:>9.2}\n",
                r.name,
                r.frame_ms_median,
                r.submit_to_fence_ms_median,
                r.texgen_ms_median,
                r.ratio_to_static_em
            );
        }
        out += "split (differences of medians):\n";
        for (what, ms) in &self.split_ms {
            out += &format!("  {what:<40} {ms:>7.2} ms\n");
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
    let views = 8u32;
    let per_view = opts.frames_per_view.max(1);
    let warmup = opts.warmup;
    // One renderer per PEM variant: switching settings re-creates slots.
    let mut renderers = vec![renderer];
    for (_, pem) in VARIANTS.iter().skip(2) {
        let Some((local, blend)) = *pem else { continue };
        let mut r = Renderer::new(&device, &scene, width, height)?;
        let mut settings = PemSettings::new(PemKind::Layered);
        settings.local_layer = local;
        settings.blend = blend;
        let layers = settings.layers();
        let source = crate::compile::map_source(&ctx, &opts.pem, &layers)?;
        r.set_pem(&scene, settings, source)?;
        renderers.push(r);
    }
    let mut logs: Vec<PerfLog> = VARIANTS.iter().map(|_| PerfLog::default()).collect();
    let o = &scene.orbit;
    let record = |log: &mut PerfLog, start: Instant, stats: crate::renderer::FrameStats| {
        log.record(
            start.elapsed().as_secs_f64() * 1e3,
            &stats.passes,
            stats.cpu,
        )
    };
    let progress = indicatif::ProgressBar::new(u64::from(2 * views * per_view));
    // Resident variants, interleaved view by view.
    for v in 0..views {
        let k = ((v as f32 + 0.5) / views as f32 * o.samples.saturating_sub(1) as f32) as u32;
        let eye = o.eye(o.angle_deg(k) + 0.5 * o.step_deg, 0.0);
        for i in 0..warmup + per_view {
            if i == warmup {
                // Decoding ahead, started by the new view, must not run
                // behind the timed frames.
                renderers.iter_mut().for_each(Renderer::settle);
            }
            for (index, log) in logs.iter_mut().enumerate().take(MOVING) {
                let (renderer, mode) = match index {
                    0 => (&mut renderers[0], FrameMode::Bare),
                    1 => (&mut renderers[0], FrameMode::StaticEm),
                    n => (&mut renderers[n - 1], FrameMode::Pem),
                };
                let start = Instant::now();
                let stats = renderer.frame(mode, eye, o.view(eye))?;
                if i >= warmup {
                    record(log, start, stats);
                }
            }
            if i >= warmup {
                progress.inc(1);
            }
        }
    }
    // Then the moving variant alone: one sample further every frame, its
    // maps decoded ahead while the previous frame draws.
    let last = o.samples.saturating_sub(1).max(1);
    for i in 0..warmup + views * per_view {
        let eye = o.eye(o.angle_deg(i % last) + 0.5 * o.step_deg, 0.0);
        let start = Instant::now();
        let stats = renderers[MOVING - 1].frame(FrameMode::Pem, eye, o.view(eye))?;
        if i >= warmup {
            record(&mut logs[MOVING], start, stats);
            progress.inc(1);
        }
    }
    progress.finish_and_clear();
    let size = [width, height];
    let reports: Vec<PerfReport> = logs
        .into_iter()
        .zip(VARIANTS)
        .map(|(log, (name, _))| log.report(&device.name, &scene.name, name, size, &[]))
        .collect();
    let static_ms = reports[1].frame_ms_median;
    let gpu = |i: usize| reports[i].cpu.submit_to_fence_ms_median;
    let room_ms = reports[1]
        .passes
        .iter()
        .find(|p| p.name == "room")
        .map_or(f64::NAN, |p| p.gpu_ms_median);
    let split_ms = vec![
        ("room pass (its timestamp, first pass)".to_string(), room_ms),
        (
            "static mirror pass (static-em - room)".into(),
            gpu(1) - room_ms,
        ),
        (
            "pem pass, distant layer (distant - room)".into(),
            gpu(2) - room_ms,
        ),
        ("+ local layer (layered - distant)".into(), gpu(3) - gpu(2)),
        (
            "+ blend pass (blended - layered nearest)".into(),
            gpu(4) - gpu(3),
        ),
    ];
    let rows = reports
        .into_iter()
        .map(|r| BenchRow {
            name: r.mode.clone(),
            frame_ms_median: r.frame_ms_median,
            submit_to_fence_ms_median: r.cpu.submit_to_fence_ms_median,
            texgen_ms_median: r.cpu.texgen_ms_median,
            ratio_to_static_em: r.frame_ms_median / static_ms,
            report: r,
        })
        .collect();
    let report = BenchReport {
        views,
        frames_per_view: per_view,
        rows,
        split_ms,
    };
    crate::util::files::write_json(&out.join("bench.json"), &report)?;
    Ok(report)
}
