//! The `jpeg-per-texture` baseline: each leaf as one JPEG atlas (alpha as
//! a second grey JPEG), the quality bisected to the codec's bytes.

use super::Baseline;
use super::atlas::{atlas, from_atlas, texture_peak};
use crate::error::{CodecError, Result};
use crate::input::EncodeInput;
use crate::quality::PsnrAccum;

fn jpeg_bytes(
    w: u32,
    h: u32,
    data: &[u8],
    color: image::ExtendedColorType,
    quality: u8,
) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, quality)
        .encode(data, w, h, color)
        .map_err(|e| CodecError::Baseline {
            name: "jpeg-per-texture",
            what: e.to_string(),
        })?;
    Ok(buf)
}

/// Encodes everything at one JPEG quality; returns (bytes, psnr).
fn jpeg_at(reference: &EncodeInput, quality: u8) -> Result<(u64, f64)> {
    let mut total = 0u64;
    let mut acc = PsnrAccum::default();
    for t in &reference.textures {
        let peak = texture_peak(t);
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s in 0..t.grid.len() {
            let (w, h, rgb, alpha) = atlas(t, s, peak);
            let jr = jpeg_bytes(w, h, &rgb, image::ExtendedColorType::Rgb8, quality)?;
            let ja = if t.layout.channels == 4 {
                Some(jpeg_bytes(
                    w,
                    h,
                    &alpha,
                    image::ExtendedColorType::L8,
                    quality,
                )?)
            } else {
                None
            };
            total += jr.len() as u64 + ja.as_ref().map_or(0, |a| a.len() as u64) + 4;
            let err = |e: image::ImageError| CodecError::Baseline {
                name: "jpeg-per-texture",
                what: e.to_string(),
            };
            let drgb = image::load_from_memory(&jr)
                .map_err(err)?
                .into_rgb8()
                .into_raw();
            let dalpha = match &ja {
                Some(a) => Some(
                    image::load_from_memory(a)
                        .map_err(err)?
                        .into_luma8()
                        .into_raw(),
                ),
                None => None,
            };
            from_atlas(t, peak, &drgb, dalpha.as_deref(), &mut out);
            acc.add(t.sample(s), t.layout.channels as usize, &out, 4);
        }
    }
    Ok((total, acc.psnr_db()))
}

/// Per-texture JPEG at the quality whose size is closest to `target` bytes
/// without exceeding it (or quality 1 if even that is larger).
pub fn jpeg_baseline(reference: &EncodeInput, target: u64) -> Result<Baseline> {
    Ok(jpeg_baselines(reference, &[target], &mut |_| {})?.remove(0))
}

/// [`jpeg_baseline`] at several byte targets, each quality encoded once
/// however many targets need it; `progress` hears of every encoding.
pub fn jpeg_baselines(
    reference: &EncodeInput,
    targets: &[u64],
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    let mut memo = std::collections::BTreeMap::new();
    let mut at = |q: u8| -> Result<(u64, f64)> {
        if let Some(&r) = memo.get(&q) {
            return Ok(r);
        }
        let r = jpeg_at(reference, q)?;
        progress(format!("jpeg quality {q}: {} bytes", r.0));
        memo.insert(q, r);
        Ok(r)
    };
    let raw = reference.raw_bytes();
    let mut out = Vec::new();
    for &target in targets {
        let (best_q, best) = largest_fitting(1, 95, target, &mut at)?;
        out.push(Baseline {
            name: "jpeg-per-texture".into(),
            ratio: raw as f64 / best.0 as f64,
            psnr_db: best.1,
            bytes: best.0,
            note: Some(format!(
                "quality {best_q}{}",
                if best.0 > target {
                    "; cannot reach the codec's bytes"
                } else {
                    ""
                }
            )),
            pixels: None,
            crf: None,
        });
    }
    Ok(out)
}

/// Bisection for the largest knob value in `lo..hi` whose size fits
/// `target` (size rising with the knob, like JPEG quality); `lo` if even
/// that does not fit. Returns the knob and its (bytes, PSNR).
fn largest_fitting(
    lo: u8,
    hi: u8,
    target: u64,
    eval: &mut dyn FnMut(u8) -> Result<(u64, f64)>,
) -> Result<(u8, (u64, f64))> {
    let (mut lo, mut hi) = (lo, hi);
    let mut best = eval(lo)?;
    let mut best_k = lo;
    if best.0 <= target {
        while hi > lo + 1 {
            let mid = (lo + hi) / 2;
            let r = eval(mid)?;
            if r.0 <= target {
                lo = mid;
                best = r;
                best_k = mid;
            } else {
                hi = mid;
            }
        }
    }
    Ok((best_k, best))
}
