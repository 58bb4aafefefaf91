//! One sample in the coding domain: planar images, MIP levels as residuals.
//!
//! Each `(face, mip)` image sits at the same texel offset as in
//! [`LeafLayout`] but stores its channels as planes (the DCT works per
//! plane). MIP levels above 0 are stored as residuals from the box-decimated
//! finest level (papers.md §2: inferred MIP levels are not filtered versions
//! of each other, but the decimated finest level predicts them well).

use crate::domain::{Gamma, to_domain};
use crate::input::LeafLayout;

/// Element offset of image `(face, mip)` in a planar sample.
pub fn image_offset(l: &LeafLayout, face: u32, mip: u32) -> usize {
    l.texel_offset(face, mip) * l.channels as usize
}

/// Halves a planar image (box filter; an odd last row/column is averaged
/// with itself) from `w × h` to `max(1, w/2) × max(1, h/2)`. Compiled for
/// AVX2 too, chosen at run time (same operations, same results).
pub fn box_down(src: &[f32], w: usize, h: usize, channels: usize, dst: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { box_down_avx2(src, w, h, channels, dst) };
    }
    box_down_impl(src, w, h, channels, dst)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn box_down_avx2(src: &[f32], w: usize, h: usize, channels: usize, dst: &mut [f32]) {
    box_down_impl(src, w, h, channels, dst)
}

#[inline(always)]
fn box_down_impl(src: &[f32], w: usize, h: usize, channels: usize, dst: &mut [f32]) {
    let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
    if w % 2 == 0 && h % 2 == 0 {
        // Common case, written so the compiler can vectorise it.
        for c in 0..channels {
            let s = &src[c * w * h..][..w * h];
            let d = &mut dst[c * w2 * h2..][..w2 * h2];
            for (drow, rows) in d.chunks_exact_mut(w2).zip(s.chunks_exact(2 * w)) {
                let (r0, r1) = rows.split_at(w);
                for ((o, a), b) in drow
                    .iter_mut()
                    .zip(r0.chunks_exact(2))
                    .zip(r1.chunks_exact(2))
                {
                    *o = 0.25 * ((a[0] + a[1]) + (b[0] + b[1]));
                }
            }
        }
        return;
    }
    for c in 0..channels {
        let s = &src[c * w * h..][..w * h];
        let d = &mut dst[c * w2 * h2..][..w2 * h2];
        for y in 0..h2 {
            let y0 = (2 * y).min(h - 1);
            let y1 = (2 * y + 1).min(h - 1);
            for x in 0..w2 {
                let x0 = (2 * x).min(w - 1);
                let x1 = (2 * x + 1).min(w - 1);
                d[y * w2 + x] =
                    0.25 * (s[y0 * w + x0] + s[y0 * w + x1] + s[y1 * w + x0] + s[y1 * w + x1]);
            }
        }
    }
}

/// Converts one input sample (interleaved, linear) to the coding domain.
pub fn to_planar_domain(l: &LeafLayout, sample: &[f32], gamma: Gamma) -> Vec<f32> {
    let ch = l.channels as usize;
    let mut out = vec![0.0f32; sample.len()];
    let mut px = [0.0f32; 4];
    for mip in 0..l.mips {
        let n = l.face_texels(mip);
        for face in 0..l.faces {
            let base = image_offset(l, face, mip);
            let src = &sample[base..][..n * ch];
            let dst = &mut out[base..][..n * ch];
            for (t, texel) in src.chunks_exact(ch).enumerate() {
                to_domain(gamma, texel, &mut px[..ch]);
                for c in 0..ch {
                    dst[c * n + t] = px[c];
                }
            }
        }
    }
    // MIP residuals: the prediction chain decimates the finest level only.
    for face in 0..l.faces {
        let mut pred = out[image_offset(l, face, 0)..][..l.face_texels(0) * ch].to_vec();
        for mip in 1..l.mips {
            let (w, h) = l.mip_size(mip - 1);
            let mut next = vec![0.0f32; l.face_texels(mip) * ch];
            box_down(&pred, w, h, ch, &mut next);
            let img = &mut out[image_offset(l, face, mip)..][..next.len()];
            img.iter_mut().zip(&next).for_each(|(v, p)| *v -= p);
            pred = next;
        }
    }
    out
}

/// A small stand-in for a sample (each face's finest level reduced to at
/// most 16×16) used by the greedy pyramid-order search.
pub fn proxy(l: &LeafLayout, planar: &[f32]) -> Vec<f32> {
    let ch = l.channels as usize;
    let mut out = Vec::new();
    for face in 0..l.faces {
        let (mut w, mut h) = l.mip_size(0);
        let mut cur = planar[image_offset(l, face, 0)..][..w * h * ch].to_vec();
        while w > 16 || h > 16 {
            let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
            let mut next = vec![0.0; w2 * h2 * ch];
            box_down(&cur, w, h, ch, &mut next);
            cur = next;
            (w, h) = (w2, h2);
        }
        out.extend_from_slice(&cur);
    }
    out
}
