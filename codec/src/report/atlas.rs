//! The baselines' image atlases: one sample's faces and MIP levels laid
//! out as one image, with its colour values coded through `q` over the
//! texture's range (8 bits for JPEG, 16 for video), and back.

use crate::input::ParamTexture;

#[inline]
fn q(x: f32) -> f32 {
    x.signum() * x.abs().sqrt()
}

/// Atlas of one sample: per MIP a row of faces; returns (w, h, rgb, alpha).
pub(super) fn atlas(t: &ParamTexture, s: usize, peak: QRange) -> (u32, u32, Vec<u8>, Vec<u8>) {
    let l = &t.layout;
    let ch = l.channels as usize;
    let aw = l.width as usize * l.faces as usize;
    let ah: usize = (0..l.mips).map(|m| l.mip_size(m).1).sum();
    let mut rgb = vec![0u8; aw * ah * 3];
    let mut alpha = vec![0u8; aw * ah];
    let sample = t.sample(s);
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * ch;
            for y in 0..h {
                for x in 0..w {
                    let px = &sample[o + (y * w + x) * ch..][..ch];
                    let d = (y0 + y) * aw + f * w + x;
                    for c in 0..3 {
                        rgb[d * 3 + c] = peak.code(px[c], 255.0) as u8;
                    }
                    if ch == 4 {
                        alpha[d] = (px[3] * 255.0).round().clamp(0.0, 255.0) as u8;
                    }
                }
            }
        }
        y0 += h;
    }
    (aw as u32, ah as u32, rgb, alpha)
}

/// The atlas of [`atlas`] at 16 bits per channel (`rgb48le` bytes),
/// recomputed from the sample (the 8-bit one only gives the geometry).
pub(super) fn widen(t: &ParamTexture, s: usize, peak: QRange, rgb8: &[u8]) -> Vec<u8> {
    let l = &t.layout;
    let ch = l.channels as usize;
    let aw = l.width as usize * l.faces as usize;
    let mut out = vec![0u8; rgb8.len() * 2];
    let sample = t.sample(s);
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * ch;
            for y in 0..h {
                for x in 0..w {
                    let px = &sample[o + (y * w + x) * ch..][..ch];
                    let d = (y0 + y) * aw + f * w + x;
                    for c in 0..3 {
                        let v = peak.code(px[c], 65535.0) as u16;
                        out[(d * 3 + c) * 2..][..2].copy_from_slice(&v.to_le_bytes());
                    }
                }
            }
        }
        y0 += h;
    }
    out
}

/// Inverse of [`widen`] into RGBA f32 (alpha left as is).
pub(super) fn from_atlas16(t: &ParamTexture, peak: QRange, rgb16: &[u8], out: &mut [f32]) {
    let l = &t.layout;
    let aw = l.width as usize * l.faces as usize;
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * 4;
            for y in 0..h {
                for x in 0..w {
                    let d = (y0 + y) * aw + f * w + x;
                    let px = &mut out[o + (y * w + x) * 4..][..4];
                    for (c, p) in px[..3].iter_mut().enumerate() {
                        let b = rgb16
                            .get((d * 3 + c) * 2..(d * 3 + c) * 2 + 2)
                            .unwrap_or(&[0, 0]);
                        *p = peak.value(u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0);
                    }
                }
            }
        }
        y0 += h;
    }
}

/// Inverse of [`atlas`] for decoded 8-bit images into RGBA f32.
pub(super) fn from_atlas(
    t: &ParamTexture,
    peak: QRange,
    rgb: &[u8],
    alpha: Option<&[u8]>,
    out: &mut [f32],
) {
    let l = &t.layout;
    let aw = l.width as usize * l.faces as usize;
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * 4;
            for y in 0..h {
                for x in 0..w {
                    let d = (y0 + y) * aw + f * w + x;
                    let px = &mut out[o + (y * w + x) * 4..][..4];
                    for (c, p) in px[..3].iter_mut().enumerate() {
                        *p = peak.value(rgb.get(d * 3 + c).copied().unwrap_or(0) as f32, 255.0);
                    }
                    px[3] = alpha
                        .and_then(|a| a.get(d))
                        .map_or(1.0, |&a| a as f32 / 255.0);
                }
            }
        }
        y0 += h;
    }
}

/// The range of `q` over a texture's colour values, which the 8- and
/// 16-bit atlases span: inferred maps ring below zero (on the teapot PEM
/// 14–38 % of colour values are negative, down to −21; clamping them alone
/// would cap a baseline near 29–37 dB), so the range includes negatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct QRange {
    lo: f32,
    span: f32,
}

impl QRange {
    /// Code of `x` in `0..=max`.
    fn code(self, x: f32, max: f32) -> f32 {
        ((q(x) - self.lo) / self.span * max).round().clamp(0.0, max)
    }
    /// Inverse of [`QRange::code`]: `q⁻¹` of the code's value.
    fn value(self, code: f32, max: f32) -> f32 {
        let v = code / max * self.span + self.lo;
        v * v.abs()
    }
}

pub(super) fn texture_peak(t: &ParamTexture) -> QRange {
    let ch = t.layout.channels as usize;
    let (lo, hi) = t
        .data
        .chunks_exact(ch)
        .flat_map(|p| p[..3].iter())
        .fold((0.0f32, 1e-6f32), |(lo, hi), &v| {
            (lo.min(q(v)), hi.max(q(v)))
        });
    QRange { lo, span: hi - lo }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atlas_codes_keep_negative_values() {
        let r = QRange {
            lo: -3.0,
            span: 8.0,
        }; // q in -3..=5: x in -9..=25
        for x in [-9.0f32, -0.25, 0.0, 1.0, 24.9, 25.0] {
            for max in [255.0, 65535.0] {
                let back = r.value(r.code(x, max), max);
                // Half a code step in q, mapped through q⁻¹.
                let dq = 0.5 * r.span / max;
                let tol = 2.0 * x.abs().sqrt() * dq + dq * dq + 1e-6;
                assert!((back - x).abs() <= tol, "{x} -> {back} ({max})");
            }
        }
        assert_eq!(r.code(-100.0, 255.0), 0.0);
        assert_eq!(r.code(100.0, 255.0), 255.0);
    }
}
