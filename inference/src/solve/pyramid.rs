//! Pyramidal regularization Γ(x) = Σ_{l < last} ‖level_l − up(level_{l+1})‖²
//! (thesis eq. 3.9), as a sparse matrix `P` with Γ(x) = ‖P x‖².
//!
//! `up` is bilinear interpolation of the next coarser level at each finer
//! texel centre (weights ¾/¼ for exact halving), clamped to the edge of the
//! same face. Cube faces are regularized independently: no coupling across
//! face edges, so seams are left to the data term. Consequence: a cube face
//! (or a top-level texel) that no pixel influences is in the null space of
//! the operator; CG leaves that component at its start value (0 when cold).

use super::csr::{CsrBuilder, CsrMatrix};
use super::layout::TextureLayout;

/// `P`: one row per texel of every level but the last, `len()` columns.
pub fn pyramid_matrix(layout: &TextureLayout) -> CsrMatrix {
    let mut b = CsrBuilder::new(layout.len());
    let mut row = Vec::with_capacity(5);
    for level in 0..layout.levels().saturating_sub(1) {
        let (w, h) = layout.level_size(level);
        let (cw, ch) = layout.level_size(level + 1);
        let xs: Vec<_> = (0..w).map(|x| taps(x, w, cw)).collect();
        let ys: Vec<_> = (0..h).map(|y| taps(y, h, ch)).collect();
        for face in 0..layout.faces() {
            let fine = layout.block_offset(face, level);
            let coarse = layout.block_offset(face, level + 1);
            for (y, &(y0, y1, fy)) in ys.iter().enumerate() {
                for (x, &(x0, x1, fx)) in xs.iter().enumerate() {
                    row.clear();
                    row.push(((fine + y * w as usize + x) as u32, 1.0f32));
                    for (cy, wy) in [(y0, 1.0 - fy), (y1, fy)] {
                        for (cx, wx) in [(x0, 1.0 - fx), (x1, fx)] {
                            let c = coarse + cy as usize * cw as usize + cx as usize;
                            row.push((c as u32, -(wy * wx)));
                        }
                    }
                    // Columns come from the layout, so they are in range.
                    let _ = b.push_row(&row);
                }
            }
        }
    }
    b.finish()
}

/// Bilinear taps on the coarse axis for fine texel `i`: (lo, hi, weight of hi).
pub(crate) fn taps(i: u32, n: u32, cn: u32) -> (u32, u32, f32) {
    let u = (i as f32 + 0.5) * cn as f32 / n as f32 - 0.5;
    let lo = u.floor();
    let f = u - lo;
    let clamp = |v: f32| v.clamp(0.0, (cn - 1) as f32) as u32;
    (clamp(lo), clamp(lo + 1.0), f)
}

/// Γ(x) evaluated directly (diagnostics and tests).
pub fn gamma(layout: &TextureLayout, x: &[f32]) -> f64 {
    let p = pyramid_matrix(layout);
    let mut px = vec![0.0f64; p.rows];
    let xd: Vec<f64> = x.iter().map(|&v| v as f64).collect();
    p.mul(&xd, &mut px);
    px.iter().map(|v| v * v).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::layout::TextureShape;

    #[test]
    fn constant_and_linear_ramps_have_zero_energy_inside() {
        let l = TextureLayout::full_chain(TextureShape::Cube { size: 8 });
        let p = pyramid_matrix(&l);
        assert_eq!(p.cols, l.len());
        assert_eq!(p.rows, l.len() - 6);
        assert_eq!(gamma(&l, &vec![0.7; l.len()]), 0.0);
        for r in 0..p.rows {
            let s: f32 = p.values[p.row_ptr[r]..p.row_ptr[r + 1]].iter().sum();
            assert!(s.abs() < 1e-6, "row {r} sums to {s}");
        }
    }

    #[test]
    fn exact_halving_uses_three_quarter_weights() {
        let l = TextureLayout::full_chain(TextureShape::Tex2D {
            width: 4,
            height: 4,
        });
        let p = pyramid_matrix(&l);
        // Interior fine texel (1,1) sits ¾ from coarse (0,0), ¼ from (1,1).
        let r = l.index(0, 0, 1, 1);
        let row: Vec<_> = (p.row_ptr[r]..p.row_ptr[r + 1])
            .map(|k| (p.col_idx[k] as usize, p.values[k]))
            .collect();
        let c = |x, y| l.index(0, 1, x, y);
        assert!(row.contains(&(r, 1.0)));
        assert!(row.contains(&(c(0, 0), -0.5625)));
        assert!(row.contains(&(c(1, 1), -0.0625)));
        assert!(row.contains(&(c(1, 0), -0.1875)));
    }

    #[test]
    fn a_spike_has_positive_energy() {
        let l = TextureLayout::full_chain(TextureShape::Tex2D {
            width: 8,
            height: 4,
        });
        let mut x = vec![0.0; l.len()];
        x[l.index(0, 0, 3, 2)] = 1.0;
        assert!(gamma(&l, &x) >= 1.0);
    }
}
