//! The forward-mapping baseline (thesis §3, papers.md §1): map each texel to
//! where it lands in the image, filter the target image there with a
//! Lanczos kernel (half-width 4 pixels), and fill texels no pixel places
//! by pull-push through the MIP chain.
//!
//! A texel's image position is the weight-averaged position of the pixels
//! whose rows of A sample it, so the baseline sees the same visibility and
//! texgen as least squares. Every MIP level is mapped, not only the finest:
//! where the view minifies, trilinear filtering reads coarse levels, and a
//! chain box-filtered from a hole-filled finest level looks blocky there.

use crate::solve::csr::CsrMatrix;
use crate::solve::layout::TextureLayout;

pub const LANCZOS_HALF_WIDTH: f32 = 4.0;

fn lanczos(x: f32, a: f32) -> f32 {
    let x = x.abs();
    if x < 1e-6 {
        1.0
    } else if x >= a {
        0.0
    } else {
        let px = std::f32::consts::PI * x;
        a * px.sin() * (px / a).sin() / (px * px)
    }
}

/// One channel of the forward-mapped texture. `target[p]` is the target
/// value at pixel p (row-major, `width` wide); `object[p]` says whether p
/// belongs to the object (taps outside it are left out and the kernel
/// renormalised); `pixels[row]` is the pixel of each row of `a`.
pub fn forward_map(
    a: &CsrMatrix,
    pixels: &[u32],
    layout: &TextureLayout,
    width: u32,
    target: &[f32],
    object: &[bool],
) -> Vec<f32> {
    // Accumulate Σ w·(x, y) and Σ w for every texel of every level: where
    // the image minifies, trilinear reads coarse levels, and those texels
    // are the ones the image shows.
    let n = layout.len();
    let mut sum_x = vec![0.0f64; n];
    let mut sum_y = vec![0.0f64; n];
    let mut sum_w = vec![0.0f64; n];
    for (row, &p) in pixels.iter().enumerate().take(a.rows) {
        let (px, py) = (f64::from(p % width) + 0.5, f64::from(p / width) + 0.5);
        for k in a.row_ptr[row]..a.row_ptr[row + 1] {
            let t = a.col_idx[k] as usize;
            let w = f64::from(a.values[k]);
            sum_x[t] += w * px;
            sum_y[t] += w * py;
            sum_w[t] += w;
        }
    }
    let height = (target.len() as u32).checked_div(width).unwrap_or(0);
    let mut mapped = vec![f32::NAN; n]; // NaN = no pixel places this texel
    for t in 0..n {
        if sum_w[t] <= 1e-6 {
            continue;
        }
        let cx = (sum_x[t] / sum_w[t]) as f32;
        let cy = (sum_y[t] / sum_w[t]) as f32;
        let (mut acc, mut norm) = (0.0f32, 0.0f32);
        let r = LANCZOS_HALF_WIDTH as i64;
        let (ix, iy) = (cx.floor() as i64, cy.floor() as i64);
        for y in (iy - r)..=(iy + r) {
            for x in (ix - r)..=(ix + r) {
                if x < 0 || y < 0 || x >= i64::from(width) || y >= i64::from(height) {
                    continue;
                }
                let p = (y * i64::from(width) + x) as usize;
                if !object.get(p).copied().unwrap_or(false) {
                    continue;
                }
                let k = lanczos(x as f32 + 0.5 - cx, LANCZOS_HALF_WIDTH)
                    * lanczos(y as f32 + 0.5 - cy, LANCZOS_HALF_WIDTH);
                acc += k * target[p];
                norm += k;
            }
        }
        if norm.abs() > 1e-6 {
            mapped[t] = acc / norm;
        }
    }
    fill_holes(layout, mapped)
}

/// Per face: a texel no pixel placed takes the box average of its placed
/// children at the finer level, else its parent's value (pull-push across
/// the chain); a face nobody sees is 0.
fn fill_holes(layout: &TextureLayout, mut x: Vec<f32>) -> Vec<f32> {
    let levels = layout.levels();
    for face in 0..layout.faces() {
        // Pull: coarse holes from finer placed texels.
        for level in 1..levels {
            let (w, h) = layout.level_size(level);
            let (fw, fh) = layout.level_size(level - 1);
            for y in 0..h {
                for xx in 0..w {
                    let i = layout.index(face, level, xx, y);
                    if !x[i].is_nan() {
                        continue;
                    }
                    let (mut s, mut c) = (0.0, 0);
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let v = x[layout.index(
                            face,
                            level - 1,
                            (2 * xx + dx).min(fw - 1),
                            (2 * y + dy).min(fh - 1),
                        )];
                        if !v.is_nan() {
                            s += v;
                            c += 1;
                        }
                    }
                    if c > 0 {
                        x[i] = s / c as f32;
                    }
                }
            }
        }
        // Push: remaining holes from the parent, coarse to fine.
        for level in (0..levels.saturating_sub(1)).rev() {
            let (w, h) = layout.level_size(level);
            let (cw, ch) = layout.level_size(level + 1);
            for y in 0..h {
                for xx in 0..w {
                    let i = layout.index(face, level, xx, y);
                    if x[i].is_nan() {
                        x[i] = x[layout.index(
                            face,
                            level + 1,
                            (xx / 2).min(cw - 1),
                            (y / 2).min(ch - 1),
                        )];
                    }
                }
            }
        }
        for level in 0..levels {
            let (w, h) = layout.level_size(level);
            for y in 0..h {
                for xx in 0..w {
                    let i = layout.index(face, level, xx, y);
                    if x[i].is_nan() {
                        x[i] = 0.0;
                    }
                }
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::csr::CsrBuilder;
    use crate::solve::layout::TextureShape;

    #[test]
    fn lanczos_is_interpolating() {
        assert_eq!(lanczos(0.0, 4.0), 1.0);
        for i in 1..4 {
            assert!(lanczos(i as f32, 4.0).abs() < 1e-6);
        }
        assert_eq!(lanczos(4.5, 4.0), 0.0);
    }

    #[test]
    fn identity_mapping_reproduces_a_constant_and_fills_holes() {
        // A 4x4 texture seen 1:1 by a 4x4 image, except texel (3, 3).
        let layout = TextureLayout::full_chain(TextureShape::Tex2D {
            width: 4,
            height: 4,
        });
        let mut builder = CsrBuilder::new(layout.len());
        let mut pixels = Vec::new();
        for y in 0..4 {
            for x in 0..4 {
                if (x, y) == (3, 3) {
                    continue;
                }
                builder
                    .push_row(&[(layout.index(0, 0, x, y) as u32, 1.0)])
                    .expect("row");
                pixels.push(y * 4 + x);
            }
        }
        let a = builder.finish();
        let target = vec![0.5f32; 16];
        let object = vec![true; 16];
        let x = forward_map(&a, &pixels, &layout, 4, &target, &object);
        assert_eq!(x.len(), layout.len());
        for v in &x {
            assert!((v - 0.5).abs() < 1e-5, "{x:?}");
        }
    }
}
