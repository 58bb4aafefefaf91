//! Writing the caller's texels: the inverse colour and gamma transform
//! from planar coding-domain images to interleaved linear RGBA, `f32` or
//! `f16` (on AVX2/F16C where the CPU has them).

use half::f16;
use half::slice::HalfFloatSliceExt;

use crate::domain::Gamma;

/// A texel component type the decoder can write: `f32` or `half::f16`.
pub trait OutTexel: Copy + Send {
    /// Converts `src` into `dst` (same length).
    fn convert(src: &[f32], dst: &mut [Self]);
    /// A faster, bit-identical γ = 2 write of the first texels where the
    /// CPU allows (see `write_rgba`); returns how many it wrote.
    #[inline]
    fn write_gamma2(
        _img: &[f32],
        _pred: Option<&[f32]>,
        _n: usize,
        _ch: usize,
        _out: &mut [Self],
    ) -> usize {
        0
    }
}
impl OutTexel for f32 {
    #[inline]
    fn convert(src: &[f32], dst: &mut [Self]) {
        dst.copy_from_slice(src);
    }
}
impl OutTexel for f16 {
    #[inline]
    fn convert(src: &[f32], dst: &mut [Self]) {
        // SIMD (F16C) when the CPU has it.
        dst.convert_from_f32_slice(src);
    }
    #[inline]
    fn write_gamma2(
        img: &[f32],
        pred: Option<&[f32]>,
        n: usize,
        ch: usize,
        out: &mut [Self],
    ) -> usize {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("f16c") {
            // SAFETY: both features were just detected.
            return unsafe { write_gamma2_f16_avx2(img, pred, n, ch, out) };
        }
        let _ = (img, pred, n, ch, out);
        0
    }
}

/// Planar coding-domain image (the leaf's sum of levels, + the MIP
/// prediction above MIP 0) → interleaved linear RGBA, converted to `T`.
pub(super) fn write_rgba<T: OutTexel>(
    g: Gamma,
    img: &[f32],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [T],
) {
    if g.0 == 2.0 {
        let done = T::write_gamma2(img, pred, n, ch, out);
        write_rgba_with(|v: f32| v * v.abs(), img, pred, n, ch, out, done)
    } else {
        write_rgba_with(|v: f32| g.inverse(v), img, pred, n, ch, out, 0)
    }
}

/// The portable write, from texel `from` on.
#[inline(always)]
fn write_rgba_with<T: OutTexel>(
    inv: impl Fn(f32) -> f32,
    img: &[f32],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [T],
    from: usize,
) {
    const CHUNK: usize = 256;
    if from >= n {
        return;
    }
    let mut tmp = [0.0f32; CHUNK * 4];
    let mut sum = [[0.0f32; CHUNK]; 4];
    for (chunk_i, dst) in out[from * 4..n * 4].chunks_mut(CHUNK * 4).enumerate() {
        let base = from + chunk_i * CHUNK;
        let m = dst.len() / 4;
        // Planes (+ prediction) for this chunk, then the colour transform.
        for (c, s) in sum.iter_mut().enumerate() {
            let s = &mut s[..m];
            if c >= ch {
                s.fill(1.0);
                continue;
            }
            s.copy_from_slice(&img[c * n + base..][..m]);
            if let Some(p) = pred {
                s.iter_mut()
                    .zip(&p[c * n + base..][..m])
                    .for_each(|(a, b)| *a += b);
            }
        }
        // Colour transform in place (planar, vectorisable), then interleave.
        let [y, co, cg, a] = &mut sum;
        for ((y, co), cg) in y[..m].iter_mut().zip(&mut co[..m]).zip(&mut cg[..m]) {
            let t = *y - *cg;
            let (r, g, b) = (inv(t + *co), inv(*y + *cg), inv(t - *co));
            (*y, *co, *cg) = (r, g, b);
        }
        for (px, ((r, g), (b, a))) in tmp[..m * 4]
            .chunks_exact_mut(4)
            .zip(y[..m].iter().zip(&co[..m]).zip(cg[..m].iter().zip(&a[..m])))
        {
            px.copy_from_slice(&[*r, *g, *b, *a]);
        }
        T::convert(&tmp[..m * 4], dst);
    }
}

/// [`write_rgba`] for γ = 2 into f16, eight texels at a time on AVX2/F16C
/// (the same operations in the same order as the portable path, and the
/// same round-to-nearest-even conversion as `half`, so the same bits).
/// Returns how many texels it wrote (a multiple of 8; the rest is left to
/// the portable path).
///
/// # Safety
/// The CPU must support AVX2 and F16C.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,f16c")]
unsafe fn write_gamma2_f16_avx2(
    img: &[f32],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [f16],
) -> usize {
    use std::arch::x86_64::*;
    let n8 = n / 8 * 8;
    let planes = &img[..n * ch];
    let pred = pred.map(|p| &p[..n * ch]);
    let out = &mut out[..n8 * 4];
    // SAFETY: AVX2/F16C are available (the caller's contract); every load
    // reads 8 floats at `c·n + i` with `i + 8 ≤ n8 ≤ n` inside the planes
    // (length-checked above), every store writes 8 halves at `4i + 8j`,
    // `j < 4`, inside `out[..4·n8]`.
    unsafe {
        let sign = _mm256_set1_ps(-0.0);
        let inv = |v: __m256| _mm256_mul_ps(v, _mm256_andnot_ps(sign, v));
        let load = |c: usize, i: usize| {
            let v = _mm256_loadu_ps(planes.as_ptr().add(c * n + i));
            match pred {
                Some(p) => _mm256_add_ps(v, _mm256_loadu_ps(p.as_ptr().add(c * n + i))),
                None => v,
            }
        };
        let o = out.as_mut_ptr() as *mut __m128i;
        for i in (0..n8).step_by(8) {
            let (y, co, cg) = (load(0, i), load(1, i), load(2, i));
            let a = if ch > 3 {
                load(3, i)
            } else {
                _mm256_set1_ps(1.0)
            };
            let t = _mm256_sub_ps(y, cg);
            let r = inv(_mm256_add_ps(t, co));
            let g = inv(_mm256_add_ps(y, cg));
            let b = inv(_mm256_sub_ps(t, co));
            let [r, g, b, a] =
                [r, g, b, a].map(|v| _mm256_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(v));
            let rg_lo = _mm_unpacklo_epi16(r, g);
            let rg_hi = _mm_unpackhi_epi16(r, g);
            let ba_lo = _mm_unpacklo_epi16(b, a);
            let ba_hi = _mm_unpackhi_epi16(b, a);
            let q = o.add(i / 2);
            _mm_storeu_si128(q, _mm_unpacklo_epi32(rg_lo, ba_lo));
            _mm_storeu_si128(q.add(1), _mm_unpackhi_epi32(rg_lo, ba_lo));
            _mm_storeu_si128(q.add(2), _mm_unpacklo_epi32(rg_hi, ba_hi));
            _mm_storeu_si128(q.add(3), _mm_unpackhi_epi32(rg_hi, ba_hi));
        }
    }
    n8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_f16_write_matches_the_portable_one() {
        let mut seed = 3u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 40) as f32 / (1u64 << 24) as f32 - 0.3) * 40.0
        };
        // Lengths with and without an 8-texel tail; RGB and RGBA; with and
        // without a MIP prediction; values spanning f16's range and beyond.
        for (n, ch, with_pred) in [(64, 3, false), (67, 4, true), (5, 3, true), (1, 4, false)] {
            let img: Vec<f32> = (0..n * ch).map(|_| next()).collect();
            let pred: Vec<f32> = (0..n * ch).map(|_| next() * 0.1).collect();
            let pred = with_pred.then_some(&pred[..]);
            let mut fast = vec![f16::ZERO; n * 4];
            let mut portable = vec![f16::ZERO; n * 4];
            write_rgba(Gamma(2.0), &img, pred, n, ch, &mut fast);
            write_rgba_with(|v: f32| v * v.abs(), &img, pred, n, ch, &mut portable, 0);
            let bits = |v: &[f16]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&portable), "n {n}, ch {ch}");
        }
    }
}
