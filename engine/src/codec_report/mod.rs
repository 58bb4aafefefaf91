//! `engine codec-report`: a container's ratio, texture and rendered-frame
//! PSNR, decode time, and baselines at the same bytes (JPEG, MPEG-texture,
//! MPEG-view), with ratio-against-PSNR curves on request.

mod access;
mod curves;
mod frames;
mod view_frames;

pub use curves::plot_curves;

use crate::backend::DeviceOptions;
use crate::compile::encode::{MapsFor, load_input, map_keys};
use crate::maps::MapSet;
use anyhow::{Context, Result};
use curves::curves;
use frames::{FRAME_PIXELS, FrameBench};
use inference::scene::Scene;
use std::path::PathBuf;
use view_frames::{ViewFrames, mpeg_view_baselines};

/// What to measure and where the scene's compiled inputs are.
#[derive(Clone, Debug)]
pub struct CodecReportRequest {
    /// The container to measure.
    pub file: PathBuf,
    /// Where the JSON report goes (the chart beside it).
    pub json: PathBuf,
    /// The inferred maps the container was encoded from.
    pub infer_dir: PathBuf,
    /// Traced targets for the rendered-frame PSNR.
    pub trace_dir: PathBuf,
    /// Size the targets were traced at.
    pub size: (u32, u32),
    /// Rendered frames at every Nth sample (0: none, and no MPEG-view).
    pub frames_every: u32,
    /// Also the curves at `curve_ratios`.
    pub curve: bool,
    pub curve_ratios: Vec<f64>,
    /// The video encoders of the MPEG-texture baselines, curves and
    /// random access (each only when ffmpeg has it).
    pub videos: Vec<codec::report::VideoCodec>,
    pub device: DeviceOptions,
}

pub fn codec_report(scene: &Scene, req: &CodecReportRequest) -> Result<String> {
    crate::util::files::check_output_file(&req.json)?;
    // Its errors name the file.
    let container = codec::Container::open(&req.file)?;
    // Measured against the maps it was encoded from: refused, saying how
    // to make them, when they are not there.
    map_keys(scene, MapSet::Scene, &req.infer_dir, MapsFor::Report)?;
    let input = load_input(scene, MapSet::Scene, &req.infer_dir, MapsFor::Report)?;
    let progress = indicatif::ProgressBar::new_spinner().with_style(
        indicatif::ProgressStyle::with_template("{spinner} codec-report {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    progress.enable_steady_tick(std::time::Duration::from_millis(200));
    // Shown above the spinner, and printed even when stderr is no terminal.
    let say = |m: String| {
        progress.set_message(m.clone());
        progress.suspend(|| eprintln!("{m}"));
    };
    say("texture PSNR, decode time, JPEG and MPEG-texture baselines".into());
    // Each step printed: the video encoders' CRF tries take minutes each.
    let mut step = |m: String| say(m);
    let mut report = codec::report::report_with(
        &container,
        &input,
        &codec::report::ReportOptions {
            videos: req.videos.clone(),
            ..Default::default()
        },
        &mut step,
    )
    .with_context(|| {
        format!(
            "measuring {} against the maps in {}",
            req.file.display(),
            req.infer_dir.display()
        )
    })?;
    say("rendered frames".into());
    let mut bench = FrameBench::new(req, scene)?;
    add_rendered_frames(&mut report, bench.as_mut(), &container, req.frames_every)?;
    if let Some(b) = bench.as_mut() {
        say("decode under load".into());
        access::add_decode_under_load(&mut report, b, &container)?;
    }
    let ffmpeg = codec::report::ffmpeg_available();
    access::add_random_access(&mut report, &req.file, &input, ffmpeg, &say)?;
    let mut views = add_view_baselines(
        scene,
        req,
        &mut report,
        bench.as_ref(),
        ffmpeg,
        input.raw_bytes(),
        &say,
    )?;
    if req.curve {
        let mut notes = Vec::new();
        report.curves = curves(
            req,
            &input,
            bench.as_mut(),
            views.as_mut(),
            ffmpeg,
            &say,
            &mut notes,
        )?;
        report.notes.append(&mut notes);
    }
    progress.finish_and_clear();
    crate::util::files::write_json(&req.json, &report)?;
    inference::key::write_record(&req.json, &inference::key::Key::new())?;
    if !report.curves.is_empty() {
        plot_curves(&req.json.with_extension("png"), &report.curves)?;
    }
    Ok(summary(req, &report))
}

/// The rendered-frame PSNR of the container's distant layer against the
/// traced layer, when traced targets exist (none are read with
/// `--frames-every 0`).
fn add_rendered_frames(
    report: &mut codec::report::CodecReport,
    bench: Option<&mut FrameBench>,
    container: &codec::Container,
    frames_every: u32,
) -> Result<()> {
    match bench {
        Some(b) => {
            let (decoded, vs_raw) = b.decoded_db(container)?;
            let raw = b.raw_db();
            let n = b.items.len();
            report.frames_psnr_db = Some(decoded);
            report.frames_vs_uncompressed_psnr_db = Some(vs_raw);
            report.notes.push(format!(
                "rendered frames: distant layer at {n} samples, decoded {decoded:.2} dB vs uncompressed {raw:.2} dB (medians, against the traced layer); decoded against uncompressed rendered the same way: {vs_raw:.2} dB (compression alone); pixels: {FRAME_PIXELS}"
            ));
        }
        None if frames_every == 0 => report
            .notes
            .push("rendered frames: skipped (--frames-every 0)".into()),
        None => report
            .notes
            .push("rendered frames: no traced targets found (see --trace-dir, --size)".into()),
    }
    Ok(())
}

/// The MPEG-view baselines (ffmpeg on the traced images), when ffmpeg and
/// rendered frames exist; the traced images are kept for the curves.
fn add_view_baselines(
    scene: &Scene,
    req: &CodecReportRequest,
    report: &mut codec::report::CodecReport,
    bench: Option<&FrameBench>,
    ffmpeg: bool,
    raw_bytes: u64,
    say: &dyn Fn(String),
) -> Result<Option<ViewFrames>> {
    let mut views = None;
    match (bench, ffmpeg) {
        (_, false) => {
            say("ffmpeg not on PATH: mpeg-view baseline skipped".into());
        }
        (None, true) => report.notes.push(
            "mpeg-view skipped: it measures the rendered frames' pixels, and there are none".into(),
        ),
        (Some(b), true) => {
            say("mpeg-view: reading the traced images".into());
            let measured: Vec<u32> = b.items.iter().map(|i| i.k).collect();
            match ViewFrames::load(
                &req.trace_dir,
                scene.orbit.sample_count(),
                req.size,
                &measured,
                say,
            ) {
                Ok(mut v) => {
                    // The thesis compared at the same ratio, each against its
                    // own raw data; the images are about 4x smaller raw.
                    let own_raw = v.frames.len() as f64 * f64::from(v.width * v.height) * 12.0;
                    let targets = [
                        ("mpeg-view", report.bytes),
                        ("mpeg-view-same-ratio", (own_raw / report.ratio) as u64),
                    ];
                    let mut bs = mpeg_view_baselines(&mut v, b, raw_bytes, &targets, say)?;
                    report.baselines.append(&mut bs);
                    views = Some(v);
                }
                Err(e) => report.notes.push(format!("mpeg-view skipped: {e:#}")),
            }
        }
    }
    Ok(views)
}

/// The report's lines for stdout.
fn summary(req: &CodecReportRequest, report: &codec::report::CodecReport) -> String {
    let mut text = format!(
        "{}: ratio {:.1}:1 ({:.1}:1 against 8-bit), texture PSNR {:.2} dB, decode {:.2} ms per leaf (median)\n",
        req.file.display(),
        report.ratio,
        report.ratio_vs_8bit,
        report.psnr_db,
        report.decode_ms_median
    );
    if let Some(n) = report
        .notes
        .iter()
        .find(|n| n.starts_with("rendered frames"))
    {
        text += &format!("  {n}\n");
    }
    if let (Some(p50), Some(p95)) = (
        report.decode_ms_p50_under_load,
        report.decode_ms_p95_under_load,
    ) {
        text += &format!("  decode while rendering: p50 {p50:.2} ms, p95 {p95:.2} ms per leaf\n");
    }
    for a in &report.random_access {
        text += &format!(
            "  random access {:<17} {:.2} ms, {} bytes read (medians over {} samples)\n",
            a.name, a.ms, a.bytes_read, a.samples
        );
    }
    for b in &report.baselines {
        text += &format!(
            "  baseline {:<24} ratio {:.1}:1, PSNR {:.2} dB\n",
            b.name, b.ratio, b.psnr_db
        );
    }
    for c in &report.curves {
        text += &format!("  curve {:<24} ({}):", c.name, c.metric);
        for p in &c.points {
            text += &format!(" {:.0}:1 {:.2} dB;", p.ratio, p.psnr_db);
        }
        text += "\n";
    }
    text
}
