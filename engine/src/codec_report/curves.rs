//! Ratio-against-PSNR curves of the codec and the baselines at the same
//! bytes, and their chart.

use super::CodecReportRequest;
use super::frames::{FRAME_PIXELS, FrameBench};
use super::view_frames::{ViewFrames, mpeg_view_baselines};
use anyhow::Result;
use codec::{EncodeInput, EncodeOptions, Target};
use std::path::Path;

/// Ratio-against-PSNR curves: the scene encoded at each ratio (one
/// analysis), the codec's texture and rendered-frame PSNR, and the
/// baselines at the same bytes.
#[allow(clippy::too_many_arguments)]
pub(super) fn curves(
    req: &CodecReportRequest,
    input: &EncodeInput,
    bench: Option<&mut FrameBench>,
    views: Option<&mut ViewFrames>,
    ffmpeg: bool,
    say: &dyn Fn(String),
    notes: &mut Vec<String>,
) -> Result<Vec<codec::report::Curve>> {
    let ratios = &req.curve_ratios;
    say(format!(
        "curve: encoding at {} ratios (one analysis of the whole PEM, then a budget each)",
        ratios.len()
    ));
    let start = std::time::Instant::now();
    let targets: Vec<Target> = ratios.iter().map(|&r| Target::Ratio(r)).collect();
    let encoded = codec::encode_targets(input, &targets, &EncodeOptions::default())?;
    say(format!(
        "curve: encoded in {:.1} s",
        start.elapsed().as_secs_f64()
    ));
    let mut bench = bench;
    let (mut out, sizes) = codec_curves(encoded, input, bench.as_deref_mut(), say)?;
    out.extend(baseline_curves(
        input,
        &sizes,
        bench.as_deref(),
        views,
        ffmpeg.then_some(&req.videos[..]),
        say,
        notes,
    )?);
    Ok(out)
}

/// The codec's own curves at each encoded size: texture PSNR and, with
/// rendered frames, their PSNR; the sizes, for the baselines.
fn codec_curves(
    encoded: Vec<(Vec<u8>, codec::EncodeReport)>,
    input: &EncodeInput,
    mut bench: Option<&mut FrameBench>,
    say: &dyn Fn(String),
) -> Result<(Vec<codec::report::Curve>, Vec<u64>)> {
    use codec::report::{Curve, ReportOptions};
    let mut texture = Curve::new("pyramid-codec", "texture");
    let mut frames = Curve::new("pyramid-codec-frames", "frames_vs_traced");
    let mut frames_c = Curve::new("pyramid-codec-frames", "frames_vs_uncompressed");
    let mut sizes = Vec::new();
    for (bytes, _) in encoded {
        let c = codec::Container::from_bytes(bytes)?;
        let rep = codec::report::report(
            &c,
            input,
            &ReportOptions {
                jpeg_baseline: false,
                ffmpeg_baseline: false,
                videos: Vec::new(),
            },
        )?;
        texture.push(rep.ratio, rep.psnr_db, rep.bytes);
        let mut line = format!(
            "curve: ratio {:.1}:1, {} bytes: texture {:.2} dB",
            rep.ratio, rep.bytes, rep.psnr_db
        );
        if let Some(b) = bench.as_deref_mut() {
            let (db, vs_raw) = b.decoded_db(&c)?;
            frames.push(rep.ratio, db, rep.bytes);
            frames_c.push(rep.ratio, vs_raw, rep.bytes);
            line += &format!(
                ", frames {db:.2} dB against the traced layer, {vs_raw:.2} dB against the uncompressed maps"
            );
        }
        say(line);
        sizes.push(rep.bytes);
    }
    let mut out = vec![texture];
    if !frames.points.is_empty() {
        out.push(frames);
        out.push(frames_c);
    }
    Ok((out, sizes))
}

/// The baselines' curves at the codec's sizes (JPEG per texture; with
/// ffmpeg — `videos`, the encoders asked for — MPEG-texture per encoder
/// and MPEG-view), and the curves' notes.
fn baseline_curves(
    input: &EncodeInput,
    sizes: &[u64],
    bench: Option<&FrameBench>,
    views: Option<&mut ViewFrames>,
    videos: Option<&[codec::report::VideoCodec]>,
    say: &dyn Fn(String),
    notes: &mut Vec<String>,
) -> Result<Vec<codec::report::Curve>> {
    use codec::report::Curve;
    let mut out = Vec::new();
    // A baseline that cannot get as small as a target gives its smallest
    // setting for each such target: one point, not several.
    let to_curve = |name: &str, metric, bs: Vec<codec::report::Baseline>| {
        let mut c = Curve::new(name, metric);
        for b in bs {
            if c.points.iter().all(|p| p.bytes != b.bytes) {
                c.push(b.ratio, b.psnr_db, b.bytes);
            }
        }
        c
    };
    let mut say_mut = |m: String| say(m);
    out.push(to_curve(
        "jpeg-per-texture",
        "texture",
        codec::report::jpeg_baselines(input, sizes, &mut say_mut)?,
    ));
    if let Some(videos) = videos {
        for &codec in videos {
            if !codec.available() {
                notes.push(format!(
                    "curve: ffmpeg has no {}: {} skipped",
                    codec.name(),
                    codec.baseline_name()
                ));
                continue;
            }
            out.push(to_curve(
                codec.baseline_name(),
                "texture",
                codec::report::mpeg_texture_baselines_with(codec, input, sizes, &mut say_mut)?,
            ));
        }
        match (views, bench) {
            (Some(v), Some(b)) => out.push(to_curve(
                "mpeg-view",
                "frames_vs_uncompressed",
                mpeg_view_baselines(
                    v,
                    b,
                    input.raw_bytes(),
                    &sizes.iter().map(|&s| ("mpeg-view", s)).collect::<Vec<_>>(),
                    say,
                )?,
            )),
            _ => notes
                .push("curve: mpeg-view skipped (no traced images or no rendered frames)".into()),
        }
    } else {
        notes.push("curve: ffmpeg not on PATH: mpeg-texture and mpeg-view curves skipped".into());
    }
    notes.push(format!(
        "curves: a baseline that cannot get down to some of the codec's sizes has one point at its smallest; metric \"texture\" is the codec's texture PSNR (psnr_definition); the frames metrics pool {FRAME_PIXELS}: pyramid-codec-frames renders the decoded distant map against the traced distant layer (frames_vs_traced, which includes the inference's own error) and against the uncompressed map rendered the same way (frames_vs_uncompressed: compression alone); mpeg-view compares decoded against traced beauty images (its uncompressed input, so compression alone)"
    ));
    Ok(out)
}

/// The ratio-against-PSNR curves as one chart (log ratio axis): texture
/// PSNR of the codec and the texture baselines, and PSNR of rendered frames
/// against their uncompressed version (compression alone).
pub fn plot_curves(path: &Path, curves: &[codec::report::Curve]) -> Result<()> {
    use crate::eval::plot::{ChartSpec, LegendPosition, Series, xy_chart};
    let mut spec = ChartSpec::new(
        "Teapot PEM: compression ratio against PSNR",
        "compression ratio against f32 (log)",
        "PSNR (dB): textures, or frames against uncompressed",
    );
    spec.log_x = true;
    spec.legend = LegendPosition::UpperRight;
    for c in curves.iter().filter(|c| c.metric != "frames_vs_traced") {
        spec.series.push(Series {
            name: format!("{} ({})", c.name, c.metric.replace('_', " ")),
            points: c.points.iter().map(|p| (p.ratio, p.psnr_db)).collect(),
            labels: Vec::new(),
            connect: true,
        });
    }
    xy_chart(path, &spec)
}
