//! The forward-mapping baseline (thesis §3, papers.md §1): map each texel of
//! the finest level to where it lands in the image, filter the target image
//! there with a Lanczos kernel (half-width 4 pixels), fill texels no pixel
//! sees from coarser levels (pull-push), and box-filter the MIP chain.
//!
//! A texel's image position is the weight-averaged position of the pixels
//! whose rows of A sample it at the finest level, so the baseline sees the
//! same visibility and texgen as least squares.

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
    let faces = layout.faces();
    let (w0, h0) = layout.level_size(0);
    let level0 = (w0 * h0 * faces) as usize;
    // Accumulate Σ w·(x, y) and Σ w per finest-level texel.
    let mut sum_x = vec![0.0f64; level0];
    let mut sum_y = vec![0.0f64; level0];
    let mut sum_w = vec![0.0f64; level0];
    for (row, &p) in pixels.iter().enumerate().take(a.rows) {
        let (px, py) = (f64::from(p % width) + 0.5, f64::from(p / width) + 0.5);
        for k in a.row_ptr[row]..a.row_ptr[row + 1] {
            let col = a.col_idx[k] as usize;
            let (face, level, x, y) = layout.coords(col);
            if level != 0 {
                continue;
            }
            let t = ((face * h0 + y) * w0 + x) as usize;
            let w = f64::from(a.values[k]);
            sum_x[t] += w * px;
            sum_y[t] += w * py;
            sum_w[t] += w;
        }
    }
    let height = (target.len() as u32).checked_div(width).unwrap_or(0);
    let mut fine = vec![f32::NAN; level0]; // NaN = hole, filled below
    for t in 0..level0 {
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
            fine[t] = acc / norm;
        }
    }
    fill_and_build_mips(layout, fine)
}

/// Pull-push hole filling per face, then the box-filtered MIP chain, laid
/// out as `layout` orders texels.
fn fill_and_build_mips(layout: &TextureLayout, fine: Vec<f32>) -> Vec<f32> {
    let faces = layout.faces();
    let (w0, h0) = layout.level_size(0);
    let mut out = vec![0.0f32; layout.len()];
    for face in 0..faces {
        let start = (face * w0 * h0) as usize;
        let mut levels = vec![fine[start..start + (w0 * h0) as usize].to_vec()];
        // Pull: average the known texels of each 2x2 block, level by level.
        for level in 1..layout.levels() {
            let (pw, ph) = layout.level_size(level - 1);
            let (w, h) = layout.level_size(level);
            let prev = &levels[level as usize - 1];
            let mut next = vec![f32::NAN; (w * h) as usize];
            for y in 0..h {
                for x in 0..w {
                    let (mut s, mut n) = (0.0, 0);
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (sx, sy) = ((2 * x + dx).min(pw - 1), (2 * y + dy).min(ph - 1));
                        let v = prev[(sy * pw + sx) as usize];
                        if !v.is_nan() {
                            s += v;
                            n += 1;
                        }
                    }
                    if n > 0 {
                        next[(y * w + x) as usize] = s / n as f32;
                    }
                }
            }
            levels.push(next);
        }
        // Push: holes take the value of the coarser level above them;
        // a face nobody sees at all stays 0.
        for level in (0..layout.levels().saturating_sub(1)).rev() {
            let (w, h) = layout.level_size(level);
            let (cw, ch) = layout.level_size(level + 1);
            let (fine_levels, coarse_levels) = levels.split_at_mut(level as usize + 1);
            let (target, coarse) = (&mut fine_levels[level as usize], &coarse_levels[0]);
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    if target[i].is_nan() {
                        target[i] =
                            coarse[((y / 2).min(ch - 1) * cw + (x / 2).min(cw - 1)) as usize];
                    }
                }
            }
        }
        // The MIP chain of the filled finest level (not the pull averages,
        // which only fill holes).
        let mut current = levels.swap_remove(0);
        for level in 0..layout.levels() {
            let (w, h) = layout.level_size(level);
            for y in 0..h {
                for x in 0..w {
                    let v = current[(y * w + x) as usize];
                    out[layout.index(face, level, x, y)] = if v.is_nan() { 0.0 } else { v };
                }
            }
            if level + 1 < layout.levels() {
                let (nw, nh) = layout.level_size(level + 1);
                current = (0..nh)
                    .flat_map(|y| (0..nw).map(move |x| (x, y)))
                    .map(|(x, y)| {
                        let at = |dx: u32, dy: u32| {
                            let v = current
                                [((2 * y + dy).min(h - 1) * w + (2 * x + dx).min(w - 1)) as usize];
                            if v.is_nan() { 0.0 } else { v }
                        };
                        0.25 * (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1))
                    })
                    .collect();
            }
        }
    }
    out
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
