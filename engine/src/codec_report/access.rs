//! The report's two playback measurements: decode time while this device
//! renders on the same cores (playback decodes ahead on a worker while the
//! frame renders), and random access to arbitrary samples from cold, for
//! the pyramid and the video baseline at the same bytes.

use super::frames::FrameBench;
use anyhow::{Context, Result};
use codec::report::{CodecReport, VideoCodec};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Samples the random-access medians pool.
const ACCESS_SAMPLES: usize = 16;

/// Times every leaf decode along the path on a worker thread while this
/// thread keeps the device rendering the reflector (the frame bench's
/// views, from one decoded map); fills the p50 and p95 fields.
pub(super) fn add_decode_under_load(
    report: &mut CodecReport,
    bench: &mut FrameBench,
    container: &codec::Container,
) -> Result<()> {
    let done = AtomicBool::new(false);
    let (times, frames) = std::thread::scope(|scope| -> Result<(Vec<f64>, usize)> {
        let worker = scope.spawn(|| {
            let times = codec::report::path_decode_times(container, &|| true);
            done.store(true, Ordering::Release);
            times
        });
        let mut frames = 0;
        let rendered = (|| -> Result<()> {
            while !done.load(Ordering::Acquire) {
                bench.render_load(container, frames)?;
                frames += 1;
            }
            Ok(())
        })();
        let times = worker
            .join()
            .map_err(|_| anyhow::anyhow!("the decode worker panicked"))?;
        rendered?;
        Ok((times.context("decoding along the path under load")?, frames))
    })?;
    report.decode_ms_p50_under_load = Some(codec::report::quantile(&times, 0.5));
    report.decode_ms_p95_under_load = Some(codec::report::quantile(&times, 0.95));
    report.notes.push(format!(
        "decode under load: {} leaf decodes along the path on a worker while the device rendered {frames} reflector frames on the same cores",
        times.len()
    ));
    Ok(())
}

/// Random access for the pyramid (the container at `file`, opened cold per
/// sample) and, with ffmpeg, for the `mpeg-texture` baseline at its CRF.
pub(super) fn add_random_access(
    report: &mut CodecReport,
    file: &Path,
    input: &codec::EncodeInput,
    ffmpeg: bool,
    say: &dyn Fn(String),
) -> Result<()> {
    let n = input
        .textures
        .iter()
        .map(|t| t.grid.len())
        .max()
        .unwrap_or(0);
    let samples = codec::report::spread_samples(n, ACCESS_SAMPLES);
    say(format!("random access: {} samples", samples.len()));
    // One thread as playback decodes; all cores as a seek may (the video
    // decoder uses its default threads).
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for threads in [1, cores].into_iter().take(if cores > 1 { 2 } else { 1 }) {
        report.random_access.push(
            codec::report::pyramid_random_access(file, &samples, threads)
                .with_context(|| format!("random access in {}", file.display()))?,
        );
    }
    if !ffmpeg {
        report
            .notes
            .push("random access: no video baselines (ffmpeg), pyramid only".into());
    }
    // Each video baseline measured at the codec's bytes, at its CRF there.
    let videos: Vec<(VideoCodec, u32)> = VideoCodec::ALL
        .into_iter()
        .filter_map(|codec| {
            let b = report
                .baselines
                .iter()
                .find(|b| b.name == codec.baseline_name())?;
            Some((codec, b.crf?))
        })
        .collect();
    for (codec, crf) in videos {
        say(format!("random access: {} at crf {crf}", codec.name()));
        report
            .random_access
            .push(codec::report::video_random_access(
                codec, input, crf, &samples,
            )?);
    }
    Ok(())
}
