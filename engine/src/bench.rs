//! `engine bench`: the static-EM frame against the bare pass that draws the
//! same meshes with one texture. Frames alternate between the two modes in
//! one process so machine noise hits both alike; the ratio is of medians.

use crate::cli::PlayArgs;
use crate::perf::{PerfLog, PerfReport};
use crate::play::{Session, frame_angle, open_session};
use crate::renderer::FrameMode;
use anyhow::Result;
use serde::Serialize;
use std::time::Instant;

#[derive(Serialize)]
pub struct BenchReport {
    pub static_em: PerfReport,
    pub bare: PerfReport,
    /// Median static-EM frame over median bare frame (wall, submit→fence).
    pub frame_ratio: f64,
    /// The same ratio over summed GPU pass medians.
    pub gpu_ratio: f64,
}

pub fn bench(args: &PlayArgs) -> Result<BenchReport> {
    let Session {
        scene,
        out,
        device,
        mut renderer,
    } = open_session(args)?;
    let (width, height) = args.size;
    let frames = args.frames.unwrap_or(200);
    let modes = [FrameMode::StaticEm, FrameMode::Bare];
    let mut logs = [PerfLog::default(), PerfLog::default()];
    let progress = indicatif::ProgressBar::new(u64::from(frames));
    for i in 0..args.warmup + frames {
        let eye = scene
            .orbit
            .eye(frame_angle(&scene, i % frames.max(1), frames), 0.0);
        for (mode, log) in modes.iter().zip(&mut logs) {
            let start = Instant::now();
            let stats = renderer.frame(*mode, eye, scene.orbit.view(eye))?;
            if i >= args.warmup {
                log.record(
                    start.elapsed().as_secs_f64() * 1e3,
                    &stats.passes,
                    stats.cpu,
                );
            }
        }
        if i >= args.warmup {
            progress.inc(1);
        }
    }
    progress.finish_and_clear();
    let size = [width, height];
    let [static_log, bare_log] = logs;
    let static_em = static_log.report(
        &device.name,
        &scene.name,
        "StaticEm",
        size,
        &renderer.setup_timings,
    );
    let bare = bare_log.report(&device.name, &scene.name, "Bare", size, &[]);
    let gpu = |r: &PerfReport| r.passes.iter().map(|p| p.gpu_ms_median).sum::<f64>();
    let report = BenchReport {
        frame_ratio: static_em.frame_ms_median / bare.frame_ms_median,
        gpu_ratio: gpu(&static_em) / gpu(&bare),
        static_em,
        bare,
    };
    let path = out.join("bench.json");
    std::fs::write(&path, serde_json::to_string_pretty(&report)?)?;
    Ok(report)
}
