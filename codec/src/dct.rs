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
    tw: Twiddles,
}

impl Default for Dct8 {
    fn default() -> Self {
        let t = DctPlanner::new().plan_dct2(N);
        let scratch = vec![0.0; t.get_scratch_len()];
        Self {
            t,
            scratch,
            tw: Twiddles::new(),
        }
    }
}

const S0: f32 = 0.353_553_38; // sqrt(1/8)
const SK: f32 = 0.5; // sqrt(2/8)
const S0X2: f32 = 2.0 * S0;

/// The twiddle factors of rustdct's length-8 DCT-III butterfly (and its
/// inner length-4 one), computed exactly as rustdct computes them:
/// `conj(e^{-2πi·k/n})` in f64, rounded to f32.
#[derive(Clone, Copy)]
struct Twiddles {
    t4: (f32, f32),
    t8: [(f32, f32); 2],
}

impl Twiddles {
    fn new() -> Self {
        let tw = |i: usize, n: usize| {
            let angle = std::f64::consts::PI * -2f64 / n as f64 * i as f64;
            // num_complex's from_polar(1, angle), cast, then conj.
            let (re, im) = ((1f64 * angle.cos()) as f32, (1f64 * angle.sin()) as f32);
            (re, -im)
        };
        Self {
            t4: tw(1, 16),
            t8: [tw(1, 32), tw(3, 32)],
        }
    }
}

/// Eight lanes; the 1D transforms below run on 8 independent signals at
/// once (the columns, then the rows of the transposed block).
type Lanes = [f32; N];

#[inline(always)]
fn lanes(f: impl Fn(usize) -> f32) -> Lanes {
    std::array::from_fn(f)
}

/// Orthonormal inverse DCT (scaling, then rustdct's `Type2And3Butterfly8`
/// DCT-III, operation for operation) of the 8 signals whose k-th
/// coefficients are `v[k]`, lane-wise. Every lane computes exactly what
/// rustdct computes for one signal, so results are bit-identical to it.
#[inline(always)]
fn idct8_lanes(v: &[Lanes; N], tw: &Twiddles) -> [Lanes; N] {
    const F: f32 = std::f32::consts::FRAC_1_SQRT_2;
    let x: [Lanes; N] = std::array::from_fn(|k| {
        let s = if k == 0 { S0X2 } else { SK };
        lanes(|l| v[k][l] * s)
    });
    // Evens: the length-4 DCT-III of [x0, x2, x4, x6].
    let half_0 = lanes(|l| x[0][l] * 0.5);
    let frac_1 = lanes(|l| x[4][l] * F);
    let e0 = lanes(|l| half_0[l] + frac_1[l]);
    let e2 = lanes(|l| half_0[l] - frac_1[l]);
    let (r4, i4) = tw.t4;
    let lower = lanes(|l| x[2][l] * r4 + x[6][l] * i4);
    let upper = lanes(|l| x[2][l] * i4 - x[6][l] * r4);
    let ev = [
        lanes(|l| e0[l] + lower[l]),
        lanes(|l| e2[l] + upper[l]),
        lanes(|l| e2[l] - upper[l]),
        lanes(|l| e0[l] - lower[l]),
    ];
    // Odds: a length-2 DCT-III and DST-III, then the twiddled merge.
    let n1a = lanes(|l| (x[1][l] * 2.0) * 0.5);
    let n1b = lanes(|l| (x[3][l] + x[5][l]) * F);
    let n1 = [lanes(|l| n1a[l] + n1b[l]), lanes(|l| n1a[l] - n1b[l])];
    let n3a = lanes(|l| (x[3][l] - x[5][l]) * F);
    let n3b = lanes(|l| (x[7][l] * 2.0) * 0.5);
    let n3 = [lanes(|l| n3a[l] + n3b[l]), lanes(|l| n3a[l] - n3b[l])];
    let mut out = [[0.0f32; N]; N];
    for i in 0..2 {
        let (re, im) = tw.t8[i];
        let lower4 = lanes(|l| n1[i][l] * re + n3[i][l] * im);
        let upper4 = lanes(|l| n1[i][l] * im - n3[i][l] * re);
        let (lo3, up3) = (ev[i], ev[3 - i]);
        out[i] = lanes(|l| lo3[l] + lower4[l]);
        out[7 - i] = lanes(|l| lo3[l] - lower4[l]);
        out[3 - i] = lanes(|l| up3[l] + upper4[l]);
        out[4 + i] = lanes(|l| up3[l] - upper4[l]);
    }
    out
}

#[inline(always)]
fn transpose(m: &[Lanes; N]) -> [Lanes; N] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

impl Dct8 {
    /// Forward orthonormal 2D DCT of a raster 8×8 block, in place.
    pub fn forward(&mut self, b: &mut [f32; NN]) {
        for row in b.chunks_exact_mut(N) {
            self.t.process_dct2_with_scratch(row, &mut self.scratch);
            row[0] *= S0;
            row[1..].iter_mut().for_each(|v| *v *= SK);
        }
        self.columns_forward(b);
    }

    /// Inverse of [`Dct8::forward`]: columns, then rows, each the scaled
    /// DCT-III of rustdct (bit-identical to it), eight signals at a time.
    #[inline]
    pub fn inverse(&self, b: &mut [f32; NN]) {
        let rows: [Lanes; N] = std::array::from_fn(|y| std::array::from_fn(|x| b[y * N + x]));
        // Row vectors as lanes: the column transforms, all 8 at once.
        let cols = idct8_lanes(&rows, &self.tw);
        // Transposed, the row transforms run the same way.
        let out = transpose(&idct8_lanes(&transpose(&cols), &self.tw));
        for (dst, src) in b.chunks_exact_mut(N).zip(&out) {
            dst.copy_from_slice(src);
        }
    }

    fn columns_forward(&mut self, b: &mut [f32; NN]) {
        let mut col = [0.0f32; N];
        for x in 0..N {
            for y in 0..N {
                col[y] = b[y * N + x];
            }
            self.t
                .process_dct2_with_scratch(&mut col, &mut self.scratch);
            col[0] *= S0;
            col[1..].iter_mut().for_each(|v| *v *= SK);
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

    /// The inverse this module replaced: rustdct's DCT-III per column, then
    /// per row, with the orthonormal scaling.
    fn reference_inverse(d: &mut Dct8, b: &mut [f32; NN]) {
        let mut col = [0.0f32; N];
        for x in 0..N {
            for y in 0..N {
                col[y] = b[y * N + x];
            }
            col[0] *= 2.0 * S0;
            col[1..].iter_mut().for_each(|v| *v *= SK);
            d.t.process_dct3_with_scratch(&mut col, &mut d.scratch);
            for y in 0..N {
                b[y * N + x] = col[y];
            }
        }
        for row in b.chunks_exact_mut(N) {
            row[0] *= 2.0 * S0;
            row[1..].iter_mut().for_each(|v| *v *= SK);
            d.t.process_dct3_with_scratch(row, &mut d.scratch);
        }
    }

    #[test]
    fn inverse_is_bit_identical_to_rustdct() {
        let mut d = Dct8::default();
        let mut seed = 1u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        for case in 0..2000 {
            let mut b = [0.0f32; NN];
            // Dense, sparse (a few low-frequency terms, like real blocks)
            // and wide-range blocks.
            for (i, v) in b.iter_mut().enumerate() {
                let r = next();
                *v = match case % 3 {
                    0 => r * 100.0,
                    1 if ZIGZAG[..6].contains(&i) => (r * 64.0).round() * 0.37,
                    1 => 0.0,
                    _ => r * 10f32.powi((i % 9) as i32 - 4),
                };
            }
            let mut a = b;
            reference_inverse(&mut d, &mut b);
            d.inverse(&mut a);
            for i in 0..NN {
                assert_eq!(
                    a[i].to_bits(),
                    b[i].to_bits(),
                    "case {case}, {i}: {} vs {}",
                    a[i],
                    b[i]
                );
            }
        }
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
