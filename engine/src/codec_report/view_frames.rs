//! The MPEG-view baseline: the traced images along the orbit through
//! x264, measured on the rendered frames' samples and pixels.

use super::frames::{FRAME_PIXELS, FrameBench};
use crate::maps::traced_stem;
use crate::util::stats::median;
use anyhow::{Context, Result};
use inference::trace::output;
use std::path::Path;

/// `q(x) = sign(x)·√|x|`, the transfer the MPEG baselines code in.
fn q(x: f32) -> f32 {
    x.signum() * x.abs().sqrt()
}

/// The traced images along the orbit for x264: every sample's `beauty`
/// layer as `q` scaled to 16 bits by the largest `q` of them all.
pub(super) struct ViewFrames {
    pub(super) width: u32,
    pub(super) height: u32,
    peak: f32,
    /// `rgb48le` frames in orbit order.
    pub(super) frames: Vec<Vec<u8>>,
    /// The traced beauty of the measured samples, by sample.
    reference: std::collections::BTreeMap<u32, Vec<[f32; 4]>>,
    /// (bytes, PSNR) per CRF tried so far.
    tried: std::collections::BTreeMap<u32, (u64, f64)>,
}

impl ViewFrames {
    pub(super) fn load(
        trace_dir: &Path,
        samples: u32,
        size: (u32, u32),
        measured: &[u32],
        say: &dyn Fn(String),
    ) -> Result<Self> {
        let (width, height) = size;
        let n = (width * height) as usize;
        let mut beauty = Vec::new();
        for k in 0..samples {
            let path = output::with_suffix(&traced_stem(trace_dir, k), ".exr");
            let layers = output::read_exr(&path).with_context(|| {
                format!("mpeg-view needs every traced sample: {}", path.display())
            })?;
            beauty.push(
                crate::compile::infer::targets::target_pixels(&layers, "beauty", false, n)
                    .with_context(|| format!("{}", path.display()))?,
            );
            if k % 20 == 19 {
                say(format!(
                    "mpeg-view: read {} of {samples} traced images",
                    k + 1
                ));
            }
        }
        let peak = beauty
            .iter()
            .flatten()
            .flat_map(|p| p[..3].iter())
            .fold(1e-6f32, |m, &v| m.max(q(v).abs()));
        let frames = beauty.iter().map(|img| to_rgb48(img, peak)).collect();
        let reference = measured
            .iter()
            .filter_map(|&k| beauty.get(k as usize).map(|b| (k, b.clone())))
            .collect();
        Ok(Self {
            width,
            height,
            peak,
            frames,
            reference,
            tried: std::collections::BTreeMap::new(),
        })
    }
}

/// Linear RGB(A) → `rgb48le` of `q(x) / peak` (negative values to 0).
fn to_rgb48(img: &[[f32; 4]], peak: f32) -> Vec<u8> {
    img.iter()
        .flat_map(|p| p[..3].iter())
        .flat_map(|&v| {
            let u = (q(v) / peak * 65535.0).round().clamp(0.0, 65535.0) as u16;
            u.to_le_bytes()
        })
        .collect()
}

/// Inverse of [`to_rgb48`] (alpha 1).
fn from_rgb48(frame: &[u8], peak: f32) -> Vec<[f32; 4]> {
    frame
        .chunks_exact(6)
        .map(|px| {
            let c = |i: usize| {
                let v = u16::from_le_bytes([px[2 * i], px[2 * i + 1]]) as f32 / 65535.0 * peak;
                v * v
            };
            [c(0), c(1), c(2), 1.0]
        })
        .collect()
}

/// The MPEG-view baseline at each (name, byte target): the traced images
/// along the orbit through x264 (as the MPEG-texture baseline: 10-bit
/// 4:4:4, GOP 8, CRF bisected to the largest size within the target),
/// decoded, and measured like the rendered frames — the same samples and
/// pixels — but image against image. `raw_bytes` is the scene's raw
/// texture size, so the ratio is comparable with the codec's at the same
/// bytes. Each CRF is encoded once per run, whatever asks for it.
pub(super) fn mpeg_view_baselines(
    views: &mut ViewFrames,
    bench: &FrameBench,
    raw_bytes: u64,
    targets: &[(&str, u64)],
    say: &dyn Fn(String),
) -> Result<Vec<codec::report::Baseline>> {
    use inference::infer::Target;
    let ViewFrames {
        width,
        height,
        peak,
        frames,
        reference,
        tried,
    } = views;
    let (width, height, peak) = (*width, *height, *peak);
    let own_raw = frames.len() as u64 * u64::from(width * height) * 3 * 4;
    let mut out = Vec::new();
    for &(name, target) in targets {
        let mut eval = |crf: u32| -> codec::Result<(u64, f64)> {
            if let Some(&r) = tried.get(&crf) {
                return Ok(r);
            }
            let (decoded, bytes) = codec::report::ffmpeg_round_trip(frames, width, height, crf, 8)?;
            let mut db = Vec::new();
            for it in &bench.items {
                let (Some(frame), Some(reference)) =
                    (decoded.get(it.k as usize), reference.get(&it.k))
                else {
                    continue;
                };
                let t = Target {
                    name: "beauty",
                    pixels: reference,
                    channels: 3,
                };
                db.push(inference::infer::layer::psnr_over_rows(
                    &from_rgb48(frame, peak),
                    &t,
                    &it.pixels,
                ));
            }
            let r = (bytes, median(&db));
            say(format!("mpeg-view crf {crf}: {bytes} bytes, {:.2} dB", r.1));
            tried.insert(crf, r);
            Ok(r)
        };
        let (crf, bytes, psnr_db) = codec::report::smallest_fitting_crf(
            codec::report::VideoCodec::X264.max_crf(),
            target,
            &mut eval,
        )?;
        out.push(codec::report::Baseline {
            name: name.into(),
            ratio: raw_bytes as f64 / bytes as f64,
            psnr_db,
            bytes,
            note: Some(format!(
                "libx264 yuv444p10le (10-bit), crf {crf}, GOP 8: the {} traced beauty images ({width}x{height}) along the orbit, sqrt-coded to 16 bits by their peak; ratio against the scene's raw texture bytes like the codec's (against the images' own f32 RGB: {:.1}:1); decoded against traced beauty, i.e. what compression alone costs, comparable with frames_vs_uncompressed_psnr_db (frames_psnr_db also holds the inference's own error){}",
                frames.len(),
                own_raw as f64 / bytes as f64,
                if bytes > target {
                    "; cannot reach the target bytes"
                } else {
                    ""
                }
            )),
            pixels: Some(FRAME_PIXELS.into()),
            crf: Some(crf),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_frames_survive_16_bits() {
        // HDR values over six decades, a negative one (clamped to 0) and
        // the peak itself.
        let img: Vec<[f32; 4]> = vec![
            [0.0, 1e-3, 0.5, 1.0],
            [4.0, 100.0, 900.0, 1.0],
            [-2.0, 2.5e-5, 37.0, 1.0],
        ];
        let peak = img
            .iter()
            .flat_map(|p| p[..3].iter())
            .fold(0.0f32, |m, &v| m.max(q(v).abs()));
        assert_eq!(peak, 30.0);
        let bytes = to_rgb48(&img, peak);
        assert_eq!(bytes.len(), img.len() * 6);
        let back = from_rgb48(&bytes, peak);
        for (a, b) in img.iter().zip(&back) {
            for c in 0..3 {
                let want = a[c].max(0.0);
                // One 16-bit step of q at the peak: |Δ√x| ≤ peak / 65535 / 2.
                let tol = (2.0 * want.sqrt() + 1e-3) * peak / 65535.0 + 1e-6;
                assert!((b[c] - want).abs() <= tol, "{} vs {want}", b[c]);
            }
            assert_eq!(b[3], 1.0);
        }
        assert_eq!(back[1][2], 900.0);
    }
}
