//! The `mpeg-texture` baselines: each texture's samples along the
//! parameter path as one video (x264 or x265), the CRF bisected to the
//! codec's bytes.

use super::Baseline;
use super::atlas::{QRange, atlas, from_atlas16, texture_peak, widen};
use super::ffmpeg::{VideoCodec, ffmpeg_round_trip_with, smallest_fitting_crf};
use crate::error::Result;
use crate::input::{EncodeInput, ParamTexture};
use crate::quality::PsnrAccum;

/// x264 over each texture's samples in parameter order (rows of a 2D grid
/// in zig-zag), RGB atlas per frame, one I-frame per 8 samples (the
/// pyramid's random-access granularity); alpha is not coded (taken as
/// exact, which favours the baseline). The CRF is bisected to the largest
/// total size within `target` bytes.
pub(super) fn mpeg_texture_baseline(
    codec: VideoCodec,
    reference: &EncodeInput,
    target: u64,
    progress: &mut dyn FnMut(String),
) -> Result<Baseline> {
    Ok(mpeg_texture_baselines_with(codec, reference, &[target], progress)?.remove(0))
}

/// [`mpeg_texture_baseline`] at several byte targets, each CRF encoded once
/// however many targets need it; `progress` hears of every encoding. The
/// baseline is named by [`VideoCodec::baseline_name`].
pub fn mpeg_texture_baselines_with(
    codec: VideoCodec,
    reference: &EncodeInput,
    targets: &[u64],
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    let mut memo = CrfMemo::new();
    mpeg_texture_baselines_memo(codec, reference, targets, &mut memo, progress)
}

/// (bytes, PSNR) per CRF already measured on one input.
pub type CrfMemo = std::collections::BTreeMap<u32, (u64, f64)>;

/// [`mpeg_texture_baselines_with`] reusing and filling `memo` (which must
/// come from the same input and encoder), so measurement runs can keep it.
pub fn mpeg_texture_baselines_memo(
    codec: VideoCodec,
    reference: &EncodeInput,
    targets: &[u64],
    memo: &mut CrfMemo,
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    let raw_total = reference.raw_bytes();
    let streams = video_streams(reference)?;
    let name = codec.baseline_name();
    let mut run = |crf: u32| -> Result<(u64, f64)> {
        if let Some(&r) = memo.get(&crf) {
            return Ok(r);
        }
        let mut bytes = 0;
        let mut acc = PsnrAccum::default();
        for VideoStream {
            texture: t,
            peak,
            order,
            frames,
            w,
            h,
        } in &streams
        {
            let (decoded, b) = ffmpeg_round_trip_with(codec, frames, *w, *h, crf, GOP)?;
            bytes += b;
            let mut out = vec![0.0f32; t.layout.texels() * 4];
            for (&s, f) in order.iter().zip(&decoded) {
                from_atlas16(t, *peak, f, &mut out);
                if t.layout.channels == 4 {
                    for (o, r) in out.chunks_exact_mut(4).zip(t.sample(s).chunks_exact(4)) {
                        o[3] = r[3];
                    }
                }
                acc.add(t.sample(s), t.layout.channels as usize, &out, 4);
            }
        }
        let r = (bytes, acc.psnr_db());
        progress(format!("{name} crf {crf}: {bytes} bytes"));
        memo.insert(crf, r);
        Ok(r)
    };
    let mut out = Vec::new();
    for &target in targets {
        let (best_crf, bytes, psnr_db) = smallest_fitting_crf(codec.max_crf(), target, &mut run)?;
        out.push(Baseline {
            name: name.into(),
            ratio: raw_total as f64 / bytes as f64,
            psnr_db,
            bytes,
            note: Some(format!(
                "{} yuv444p10le (10-bit), crf {best_crf}, GOP 8, one stream per texture, alpha not coded{}",
                codec.name(),
                if bytes > target {
                    "; cannot reach the codec's bytes"
                } else {
                    ""
                }
            )),
            pixels: None,
            crf: Some(best_crf),
        });
    }
    Ok(out)
}

/// The I-frame period of the video baselines: the pyramid's parameter
/// blocks hold 8 samples, so both decode at most one 8-sample unit.
pub const GOP: u32 = 8;

/// One texture's samples as video frames: 16-bit RGB atlases in parameter
/// order (rows of a 2D grid in zig-zag, so neighbours stay neighbours).
pub(super) struct VideoStream<'a> {
    pub texture: &'a ParamTexture,
    pub peak: QRange,
    /// Sample index (the grid's linear index) of each frame.
    pub order: Vec<usize>,
    pub frames: Vec<Vec<u8>>,
    pub w: u32,
    pub h: u32,
}

/// Every texture of `reference` as a [`VideoStream`].
pub(super) fn video_streams(reference: &EncodeInput) -> Result<Vec<VideoStream<'_>>> {
    let mut streams = Vec::new();
    for t in &reference.textures {
        let peak = texture_peak(t);
        let mut order = Vec::new();
        for s1 in 0..t.grid.n1 {
            for k in 0..t.grid.n0 {
                let s0 = if s1 % 2 == 0 { k } else { t.grid.n0 - 1 - k };
                order.push(t.grid.index([s0, s1])?);
            }
        }
        let mut frames = Vec::new();
        let (mut w, mut h) = (0, 0);
        for &s in &order {
            let (aw, ah, rgb, _) = atlas(t, s, peak);
            // 16-bit input: the 8-bit atlas would cap the baseline near 59 dB.
            frames.push(widen(t, s, peak, &rgb));
            (w, h) = (aw, ah);
        }
        streams.push(VideoStream {
            texture: t,
            peak,
            order,
            frames,
            w,
            h,
        });
    }
    Ok(streams)
}
