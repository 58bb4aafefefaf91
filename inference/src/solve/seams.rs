//! Optional cube-map seam term: Σ over texel pairs adjacent across a face
//! edge (every level) of (x_i − x_j)². Γ regularizes each face on its own;
//! this couples the faces so that a face no pixel sees is filled smoothly
//! from its neighbours instead of keeping its start value. Not in the
//! thesis, so off by default (`SolveOptions::eps_seam = 0`).

use super::csr::{CsrBuilder, CsrMatrix};
use super::layout::TextureLayout;

/// Direction of face coordinates (s, t) ∈ [−1, 1]² (Vulkan cube face
/// order and orientation, spec §16.5.4), inverse of [`cube_face_uv`].
pub fn cube_dir(face: u32, s: f64, t: f64) -> [f64; 3] {
    match face {
        0 => [1.0, -t, -s],
        1 => [-1.0, -t, s],
        2 => [s, 1.0, t],
        3 => [s, -1.0, -t],
        4 => [s, -t, 1.0],
        _ => [-s, -t, -1.0],
    }
}

/// Face and (u, v) ∈ [0, 1]² that a cube lookup with direction `d` uses.
pub fn cube_face_uv(d: [f64; 3]) -> (u32, f64, f64) {
    let [x, y, z] = d;
    let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
    let (face, sc, tc, ma) = if ax >= ay && ax >= az {
        if x > 0.0 {
            (0, -z, -y, ax)
        } else {
            (1, z, -y, ax)
        }
    } else if ay >= az {
        if y > 0.0 {
            (2, x, z, ay)
        } else {
            (3, x, -z, ay)
        }
    } else if z > 0.0 {
        (4, x, -y, az)
    } else {
        (5, -x, -y, az)
    };
    (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

/// One row `x_i − x_j` per adjacent pair across a face edge (deduplicated);
/// empty for 2D layouts.
pub fn seam_matrix(layout: &TextureLayout) -> CsrMatrix {
    let mut pairs = Vec::new();
    if layout.faces() == 6 {
        for level in 0..layout.levels() {
            let (w, _) = layout.level_size(level);
            let n = w as f64;
            for face in 0..6 {
                for y in 0..w {
                    for x in 0..w {
                        for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                            let (ox, oy) = (x as i64 + dx, y as i64 + dy);
                            if (0..w as i64).contains(&ox) && (0..w as i64).contains(&oy) {
                                continue;
                            }
                            let s = 2.0 * (ox as f64 + 0.5) / n - 1.0;
                            let t = 2.0 * (oy as f64 + 0.5) / n - 1.0;
                            let (f2, u, v) = cube_face_uv(cube_dir(face, s, t));
                            let cl = |c: f64| ((c * n).floor().max(0.0) as u32).min(w - 1);
                            let i = layout.index(face, level, x, y);
                            let j = layout.index(f2, level, cl(u), cl(v));
                            if i != j {
                                pairs.push((i.min(j) as u32, i.max(j) as u32));
                            }
                        }
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    let mut b = CsrBuilder::new(layout.len());
    for (i, j) in pairs {
        // Indices come from the layout, so they are in range.
        let _ = b.push_row(&[(i, 1.0), (j, -1.0)]);
    }
    b.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::layout::TextureShape;

    fn centre_dir(l: &TextureLayout, i: usize) -> [f64; 3] {
        let (f, lv, x, y) = l.coords(i);
        let n = l.level_size(lv).0 as f64;
        let d = cube_dir(
            f,
            2.0 * (x as f64 + 0.5) / n - 1.0,
            2.0 * (y as f64 + 0.5) / n - 1.0,
        );
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        [d[0] / len, d[1] / len, d[2] / len]
    }

    #[test]
    fn face_uv_inverts_dir() {
        for f in 0..6 {
            for (s, t) in [(0.3, -0.7), (-0.9, 0.1), (0.0, 0.0)] {
                let (f2, u, v) = cube_face_uv(cube_dir(f, s, t));
                assert_eq!(f2, f);
                assert!((2.0 * u - 1.0 - s).abs() < 1e-12 && (2.0 * v - 1.0 - t).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn pairs_are_geometric_neighbours_on_different_faces() {
        let l = TextureLayout::full_chain(TextureShape::Cube { size: 8 });
        let m = seam_matrix(&l);
        // 12 edges × size pairs per level; the 1×1 level: 12 face pairs.
        let per_level = |n: usize| 12 * n;
        assert_eq!(
            m.rows,
            per_level(8) + per_level(4) + per_level(2) + per_level(1)
        );
        for r in 0..m.rows {
            let (i, j) = (m.col_idx[2 * r] as usize, m.col_idx[2 * r + 1] as usize);
            let ((fi, li, ..), (fj, lj, ..)) = (l.coords(i), l.coords(j));
            assert!(fi != fj && li == lj);
            let (a, b) = (centre_dir(&l, i), centre_dir(&l, j));
            let cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let n = l.level_size(li).0 as f64;
            // Adjacent texel centres are about 2/n apart (≤ 90° at 1×1).
            assert!(
                cos.acos() <= 2.5 / n + 1e-9,
                "pair {i},{j} at angle {}",
                cos.acos()
            );
        }
    }
}
