//! `engine bench` on a scene with a glass object: the hybrid frame at
//! τ = 3, 5 and 10 as the main job draws it (per-sample shell maps where
//! the scene has them, composited deferred), τ = 10 drawn forward
//! (`--compositing multipass`) and from the one traced shell, beside the
//! bare frame and the static refraction EM — interleaved view by view in
//! one process, so the machine's drift hits every row alike. Glass frames
//! are bound by the CPU's vertex ray paths as much as by the device, so
//! each row reports the wait for the paths (traced ahead while the
//! previous frame renders) beside the glass passes' device time.
//!
//! Each view draws one row's frames in a run, not one frame of every row
//! in turn: a row's next frame's paths run on a worker while its frame
//! renders, and would otherwise run on into the other rows' frames. Every
//! frame of a run announces the next (the same view), as playback does,
//! so its last frame too shares the cores with a worker; after the run,
//! untimed, that worker is waited for and its paths dropped (the next
//! run's first frame traces in line: a warm-up frame).

use super::{BenchKind, BenchOptions, BenchReport, rows};
use crate::compile::CompileContext;
use crate::options::{Mode, PemOptions, TraceFrames};
use crate::pem::settings::Compositing;
use crate::perf::{PerfLog, PerfReport};
use crate::renderer::{FrameMode, Renderer};
use anyhow::Result;
use std::time::Instant;

/// The rows, in table order: name, mode, τ, compositing, traced shell.
const ROWS: [(&str, Mode, f32, Compositing, bool); 7] = [
    ("bare", Mode::Bare, 0.0, Compositing::Deferred, false),
    (
        "static-em",
        Mode::StaticEm,
        0.0,
        Compositing::Deferred,
        false,
    ),
    (
        "hybrid, tau 3",
        Mode::Hybrid,
        3.0,
        Compositing::Deferred,
        false,
    ),
    (
        "hybrid, tau 5",
        Mode::Hybrid,
        5.0,
        Compositing::Deferred,
        false,
    ),
    (
        "hybrid, tau 10",
        Mode::Hybrid,
        10.0,
        Compositing::Deferred,
        false,
    ),
    (
        "hybrid, tau 10, multipass",
        Mode::Hybrid,
        10.0,
        Compositing::Multipass,
        false,
    ),
    (
        "hybrid, tau 10, traced shell",
        Mode::Hybrid,
        10.0,
        Compositing::Deferred,
        true,
    ),
];

/// Every row at `views` views between orbit samples at `elevation`
/// degrees; `first` draws the bare and static-EM rows.
pub fn bench(
    ctx: &CompileContext,
    device: &crate::backend::Device,
    opts: &BenchOptions,
    first: Renderer,
    elevation: f32,
) -> Result<BenchReport> {
    let scene = ctx.scene;
    check_flags(&opts.pem)?;
    if scene.objects.iter().any(|o| o.em.is_some()) {
        eprintln!(
            "{}: benching the glass; its reflectors draw static EMs in every row (a scene without glass benches reflectors)",
            scene.name
        );
    }
    let mut renderers = renderers(ctx, device, opts, first)?;
    let rows_drawn = drawn_rows(&renderers);
    let views = 8u32;
    let per_view = opts.frames_per_view.max(1);
    let mut logs: Vec<PerfLog> = rows_drawn.iter().map(|_| PerfLog::default()).collect();
    let progress =
        indicatif::ProgressBar::new(u64::from(views * per_view) * rows_drawn.len() as u64);
    let o = &scene.orbit;
    let view_eye = |v: u32| {
        let k = ((v as f32 + 0.5) / views as f32 * o.samples.saturating_sub(1) as f32) as u32;
        o.eye(o.between_deg(k, 0.5), elevation)
    };
    // At least one warm-up frame: a run's first frame traces its paths in
    // line, which playback never does.
    let warmup = opts.warmup.max(1);
    for v in 0..views {
        let eye = view_eye(v);
        for (log, &index) in logs.iter_mut().zip(&rows_drawn) {
            let r = &mut renderers[index.saturating_sub(1)];
            for i in 0..warmup + per_view {
                let start = Instant::now();
                r.set_next_view(eye, o.view(eye));
                let stats = r.frame(frame_mode(ROWS[index].1), eye, o.view(eye))?;
                if i >= warmup {
                    log.record(
                        start.elapsed().as_secs_f64() * 1e3,
                        &stats.passes,
                        stats.cpu,
                    );
                    progress.inc(1);
                }
            }
            r.drop_glass_ahead();
        }
    }
    progress.finish_and_clear();
    let reports: Vec<PerfReport> = (logs.into_iter().zip(rows_drawn))
        .map(|(log, i)| log.report(&device.name, &scene.name, ROWS[i].0, ctx.size.into(), &[]))
        .collect();
    Ok(BenchReport {
        kind: BenchKind::Glass,
        views,
        elevation_deg: elevation,
        frames_per_view: per_view,
        covered_pixels: None,
        moving_covered_pixels: None,
        rows: rows(reports, 0.0, (0, 0.0)),
        room_pass: None,
        written: Vec::new(),
    })
}

/// The rows a bench draws: all, but the forward row only where per-sample
/// maps blend (elsewhere the hybrid frame is drawn forward anyway, and
/// the row would repeat the τ = 10 one).
fn drawn_rows(renderers: &[Renderer]) -> Vec<usize> {
    let blends = |i: usize| {
        (renderers
            .get(i.saturating_sub(1))
            .and_then(|r| r.glass.as_ref()))
        .is_some_and(|g| g.sample_count() > 0)
    };
    (0..ROWS.len())
        .filter(|&i| ROWS[i].3 == Compositing::Deferred || blends(i))
        .collect()
}

/// The glass bench sets τ, compositing and the shell maps per row itself:
/// flags that would set them are refused, not silently overridden.
fn check_flags(pem: &PemOptions) -> Result<()> {
    let set: Vec<&str> = [
        (pem.tau.is_some(), "--tau"),
        (pem.compositing != Compositing::Deferred, "--compositing"),
        (pem.traced_shell, "--traced-shell"),
        (pem.traced_layers, "--traced-layers"),
    ]
    .into_iter()
    .filter_map(|(given, flag)| given.then_some(flag))
    .collect();
    if !set.is_empty() {
        anyhow::bail!(
            "{}: engine bench on a glass scene measures its own rows (τ = 3, 5, 10, forward, traced shell); drop it",
            set.join(", ")
        );
    }
    Ok(())
}

/// Row `i` draws with renderer `i − 1` (the bare and static-EM rows share
/// the first): each hybrid row has its own τ, compositing and shells.
fn renderers(
    ctx: &CompileContext,
    device: &crate::backend::Device,
    opts: &BenchOptions,
    mut first: Renderer,
) -> Result<Vec<Renderer>> {
    let (width, height) = ctx.size;
    let setup = |r: &mut Renderer, (mode, tau, compositing, traced_shell)| {
        let pem = PemOptions {
            tau: (tau > 0.0).then_some(tau),
            compositing,
            traced_shell,
            ..opts.pem.clone()
        };
        crate::play::setup_mode(ctx, r, mode, &pem, TraceFrames::default()).map(|_| ())
    };
    setup(
        &mut first,
        (Mode::StaticEm, 0.0, Compositing::Deferred, false),
    )?;
    let mut renderers = vec![first];
    for &(_, mode, tau, compositing, traced_shell) in &ROWS[2..] {
        let mut r = Renderer::new(device, ctx.scene, width, height)?;
        setup(&mut r, (mode, tau, compositing, traced_shell))?;
        renderers.push(r);
    }
    Ok(renderers)
}

fn frame_mode(mode: Mode) -> FrameMode {
    match mode {
        Mode::Bare => FrameMode::Bare,
        Mode::StaticEm => FrameMode::StaticEm,
        _ => FrameMode::Hybrid,
    }
}
