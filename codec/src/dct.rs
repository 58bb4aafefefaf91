//! 8×8 block DCT, orthonormal, on one image plane.
//!
//! The 1D transforms come from `rustdct` (well kept, pure Rust, with
//! hand-written butterflies for length 8); this module only adds the 2D
//! separable pass, orthonormal scaling (so squared errors are the same in
//! both domains, which the rate allocation relies on), edge padding and the
//! zig-zag scan.

use std::sync::Arc;

use rustdct::{DctPlanner, TransformType2And3};

pub const N: usize = 8;
pub const NN: usize = 64;

/// Zig-zag scan: `ZIGZAG[i]` is the raster index of the i-th coefficient.
pub const ZIGZAG: [usize; NN] = {
    let mut z = [0usize; NN];
    let mut i = 0;
    let mut s = 0;
    while s < 2 * N - 1 {
        let mut k = 0;
        while k <= s {
            let (x, y) = if s % 2 == 0 { (k, s - k) } else { (s - k, k) };
            if x < N && y < N {
                z[i] = y * N + x;
                i += 1;
            }
            k += 1;
        }
        s += 1;
    }
    z
};

pub struct Dct8 {
    t: Arc<dyn TransformType2And3<f32>>,
    scratch: Vec<f32>,
}

impl Default for Dct8 {
    fn default() -> Self {
        let t = DctPlanner::new().plan_dct2(N);
        let scratch = vec![0.0; t.get_scratch_len()];
        Self { t, scratch }
    }
}

const S0: f32 = 0.353_553_38; // sqrt(1/8)
const SK: f32 = 0.5; // sqrt(2/8)

impl Dct8 {
    /// Forward orthonormal 2D DCT of a raster 8×8 block, in place.
    pub fn forward(&mut self, b: &mut [f32; NN]) {
        for row in b.chunks_exact_mut(N) {
            self.t.process_dct2_with_scratch(row, &mut self.scratch);
            row[0] *= S0;
            row[1..].iter_mut().for_each(|v| *v *= SK);
        }
        self.columns(b, true);
    }

    /// Inverse of [`Dct8::forward`], in place.
    pub fn inverse(&mut self, b: &mut [f32; NN]) {
        self.columns(b, false);
        for row in b.chunks_exact_mut(N) {
            row[0] *= 2.0 * S0;
            row[1..].iter_mut().for_each(|v| *v *= SK);
            self.t.process_dct3_with_scratch(row, &mut self.scratch);
        }
    }

    fn columns(&mut self, b: &mut [f32; NN], forward: bool) {
        let mut col = [0.0f32; N];
        for x in 0..N {
            for y in 0..N {
                col[y] = b[y * N + x];
            }
            if forward {
                self.t
                    .process_dct2_with_scratch(&mut col, &mut self.scratch);
                col[0] *= S0;
                col[1..].iter_mut().for_each(|v| *v *= SK);
            } else {
                col[0] *= 2.0 * S0;
                col[1..].iter_mut().for_each(|v| *v *= SK);
                self.t
                    .process_dct3_with_scratch(&mut col, &mut self.scratch);
            }
            for y in 0..N {
                b[y * N + x] = col[y];
            }
        }
    }
}

/// Blocks across and down for a `w × h` plane.
pub fn block_grid(w: usize, h: usize) -> (usize, usize) {
    (w.div_ceil(N), h.div_ceil(N))
}

/// Forward-transforms a `w × h` plane (stride `w`) into zig-zag ordered
/// coefficient blocks, padding by edge replication.
pub fn forward_plane(dct: &mut Dct8, plane: &[f32], w: usize, h: usize) -> Vec<f32> {
    let (bw, bh) = block_grid(w, h);
    let mut out = vec![0.0; bw * bh * NN];
    let mut b = [0.0f32; NN];
    for by in 0..bh {
        for bx in 0..bw {
            for y in 0..N {
                let sy = (by * N + y).min(h - 1);
                for x in 0..N {
                    let sx = (bx * N + x).min(w - 1);
                    b[y * N + x] = plane[sy * w + sx];
                }
            }
            dct.forward(&mut b);
            let o = &mut out[(by * bw + bx) * NN..][..NN];
            for (i, &r) in ZIGZAG.iter().enumerate() {
                o[i] = b[r];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zigzag_is_a_permutation_starting_right() {
        let mut seen = [false; NN];
        for &r in &ZIGZAG {
            assert!(!seen[r]);
            seen[r] = true;
        }
        assert_eq!(&ZIGZAG[..4], &[0, 1, 8, 16]);
    }

    #[test]
    fn orthonormal_round_trip_and_parseval() {
        let mut d = Dct8::default();
        let mut b = [0.0f32; NN];
        for (i, v) in b.iter_mut().enumerate() {
            *v = ((i * 37 % 11) as f32 - 5.0) * 0.3;
        }
        let orig = b;
        d.forward(&mut b);
        let e0: f32 = orig.iter().map(|v| v * v).sum();
        let e1: f32 = b.iter().map(|v| v * v).sum();
        assert!((e0 - e1).abs() < 1e-3 * e0, "{e0} vs {e1}");
        d.inverse(&mut b);
        for i in 0..NN {
            assert!((b[i] - orig[i]).abs() < 1e-4);
        }
        let mut c = [1.0f32; NN];
        d.forward(&mut c);
        assert!((c[0] - 8.0).abs() < 1e-4);
    }
}
