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

macro_rules! lanewise {
    ($out:ident[$l:ident] = $e:expr) => {
        for $l in 0..N {
            $out[$l] = $e;
        }
    };
}

/// Orthonormal inverse DCT (scaling, then rustdct's `Type2And3Butterfly8`
/// DCT-III, operation for operation) of the 8 signals whose k-th
/// coefficients are `v[k]`, lane-wise, in place. Every lane computes
/// exactly what rustdct computes for one signal, so results are
/// bit-identical to it.
#[inline(always)]
fn idct8_lanes(v: &mut [Lanes; N], tw: &Twiddles) {
    const F: f32 = std::f32::consts::FRAC_1_SQRT_2;
    let [x0, x1, x2, x3, x4, x5, x6, x7] = v;
    x0.iter_mut().for_each(|v| *v *= S0X2);
    for x in [&mut *x1, x2, x3, x4, x5, x6, x7] {
        x.iter_mut().for_each(|v| *v *= SK);
    }
    let (x0, x1, x2, x3, x4, x5, x6, x7) = (*x0, *x1, *x2, *x3, *x4, *x5, *x6, *x7);
    let mut t = [[0.0f32; N]; 16];
    let [
        e0,
        e1,
        e2,
        e3,
        ev0,
        ev1,
        ev2,
        ev3,
        n1a,
        n1b,
        n3a,
        n3b,
        o0,
        o1,
        o2,
        o3,
    ] = &mut t;
    // Evens: the length-4 DCT-III of [x0, x2, x4, x6].
    let (r4, i4) = tw.t4;
    lanewise!(e0[l] = x0[l] * 0.5 + x4[l] * F);
    lanewise!(e2[l] = x0[l] * 0.5 - x4[l] * F);
    lanewise!(e1[l] = x2[l] * r4 + x6[l] * i4);
    lanewise!(e3[l] = x2[l] * i4 - x6[l] * r4);
    lanewise!(ev0[l] = e0[l] + e1[l]);
    lanewise!(ev1[l] = e2[l] + e3[l]);
    lanewise!(ev2[l] = e2[l] - e3[l]);
    lanewise!(ev3[l] = e0[l] - e1[l]);
    // Odds: a length-2 DCT-III and DST-III, then the twiddled merge.
    lanewise!(n1a[l] = (x1[l] * 2.0) * 0.5 + (x3[l] + x5[l]) * F);
    lanewise!(n1b[l] = (x1[l] * 2.0) * 0.5 - (x3[l] + x5[l]) * F);
    lanewise!(n3a[l] = (x3[l] - x5[l]) * F + (x7[l] * 2.0) * 0.5);
    lanewise!(n3b[l] = (x3[l] - x5[l]) * F - (x7[l] * 2.0) * 0.5);
    let ((r0, i0), (r1, i1)) = (tw.t8[0], tw.t8[1]);
    lanewise!(o0[l] = n1a[l] * r0 + n3a[l] * i0);
    lanewise!(o1[l] = n1a[l] * i0 - n3a[l] * r0);
    lanewise!(o2[l] = n1b[l] * r1 + n3b[l] * i1);
    lanewise!(o3[l] = n1b[l] * i1 - n3b[l] * r1);
    let [y0, y1, y2, y3, y4, y5, y6, y7] = v;
    lanewise!(y0[l] = ev0[l] + o0[l]);
    lanewise!(y7[l] = ev0[l] - o0[l]);
    lanewise!(y3[l] = ev3[l] + o1[l]);
    lanewise!(y4[l] = ev3[l] - o1[l]);
    lanewise!(y1[l] = ev1[l] + o2[l]);
    lanewise!(y6[l] = ev1[l] - o2[l]);
    lanewise!(y2[l] = ev2[l] + o3[l]);
    lanewise!(y5[l] = ev2[l] - o3[l]);
}

#[inline(always)]
#[allow(clippy::needless_range_loop)] // the index pairs are the point
fn transpose(m: &mut [Lanes; N]) {
    for i in 0..N {
        for j in i + 1..N {
            let t = m[i][j];
            m[i][j] = m[j][i];
            m[j][i] = t;
        }
    }
}

/// The same inverse as [`Dct8::inverse`] (the same operations in the
/// same order on every lane, so bit-identical), on AVX registers: one row
/// per register for the column pass, an 8×8 transpose, the row pass, and
/// the transpose back.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn inverse_avx2(dct: &Dct8, b: &mut [f32; NN]) {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 is available (the caller's contract); every load and
    // store is 8 floats inside the 64-float block.
    unsafe {
        let p = b.as_mut_ptr();
        let mut r: [__m256; N] = std::array::from_fn(|y| _mm256_loadu_ps(p.add(y * N)));
        pass_avx2(&mut r, &dct.tw);
        transpose_avx2(&mut r);
        pass_avx2(&mut r, &dct.tw);
        transpose_avx2(&mut r);
        for (y, v) in r.iter().enumerate() {
            _mm256_storeu_ps(p.add(y * N), *v);
        }
    }
}

/// One 1D inverse pass of [`inverse_avx2`] on eight lanes at once.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn pass_avx2(x: &mut [std::arch::x86_64::__m256; N], tw: &Twiddles) {
    use std::arch::x86_64::*;
    // Arithmetic intrinsics are safe here from Rust 1.87 on; the block
    // keeps the declared MSRV (1.85) building.
    #[allow(unused_unsafe)]
    unsafe {
        let c = _mm256_set1_ps;
        let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
        let f = c(std::f32::consts::FRAC_1_SQRT_2);
        let (half, two) = (c(0.5), c(2.0));
        x[0] = mul(x[0], c(S0X2));
        for v in &mut x[1..] {
            *v = mul(*v, c(SK));
        }
        let (r4, i4) = (c(tw.t4.0), c(tw.t4.1));
        let e0 = add(mul(x[0], half), mul(x[4], f));
        let e2 = sub(mul(x[0], half), mul(x[4], f));
        let e1 = add(mul(x[2], r4), mul(x[6], i4));
        let e3 = sub(mul(x[2], i4), mul(x[6], r4));
        let ev0 = add(e0, e1);
        let ev1 = add(e2, e3);
        let ev2 = sub(e2, e3);
        let ev3 = sub(e0, e1);
        let h1 = mul(mul(x[1], two), half);
        let s35 = mul(add(x[3], x[5]), f);
        let d35 = mul(sub(x[3], x[5]), f);
        let h7 = mul(mul(x[7], two), half);
        let n1a = add(h1, s35);
        let n1b = sub(h1, s35);
        let n3a = add(d35, h7);
        let n3b = sub(d35, h7);
        let (r0, i0) = (c(tw.t8[0].0), c(tw.t8[0].1));
        let (r1, i1) = (c(tw.t8[1].0), c(tw.t8[1].1));
        let o0 = add(mul(n1a, r0), mul(n3a, i0));
        let o1 = sub(mul(n1a, i0), mul(n3a, r0));
        let o2 = add(mul(n1b, r1), mul(n3b, i1));
        let o3 = sub(mul(n1b, i1), mul(n3b, r1));
        *x = [
            add(ev0, o0),
            add(ev1, o2),
            add(ev2, o3),
            add(ev3, o1),
            sub(ev3, o1),
            sub(ev2, o3),
            sub(ev1, o2),
            sub(ev0, o0),
        ];
    }
}

/// 8×8 transpose of eight AVX registers (rows to columns).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn transpose_avx2(r: &mut [std::arch::x86_64::__m256; N]) {
    use std::arch::x86_64::*;
    #[allow(unused_unsafe)]
    unsafe {
        let t0 = _mm256_unpacklo_ps(r[0], r[1]);
        let t1 = _mm256_unpackhi_ps(r[0], r[1]);
        let t2 = _mm256_unpacklo_ps(r[2], r[3]);
        let t3 = _mm256_unpackhi_ps(r[2], r[3]);
        let t4 = _mm256_unpacklo_ps(r[4], r[5]);
        let t5 = _mm256_unpackhi_ps(r[4], r[5]);
        let t6 = _mm256_unpacklo_ps(r[6], r[7]);
        let t7 = _mm256_unpackhi_ps(r[6], r[7]);
        let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
        let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
        let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
        let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
        let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
        *r = [
            _mm256_permute2f128_ps::<0x20>(u0, u4),
            _mm256_permute2f128_ps::<0x20>(u1, u5),
            _mm256_permute2f128_ps::<0x20>(u2, u6),
            _mm256_permute2f128_ps::<0x20>(u3, u7),
            _mm256_permute2f128_ps::<0x31>(u0, u4),
            _mm256_permute2f128_ps::<0x31>(u1, u5),
            _mm256_permute2f128_ps::<0x31>(u2, u6),
            _mm256_permute2f128_ps::<0x31>(u3, u7),
        ];
    }
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
    #[inline(always)]
    pub fn inverse(&self, b: &mut [f32; NN]) {
        let mut m = [[0.0f32; N]; N];
        for (row, src) in m.iter_mut().zip(b.chunks_exact(N)) {
            row.copy_from_slice(src);
        }
        // Row vectors as lanes: the column transforms, all 8 at once.
        idct8_lanes(&mut m, &self.tw);
        // Transposed, the row transforms run the same way.
        transpose(&mut m);
        idct8_lanes(&mut m, &self.tw);
        transpose(&mut m);
        for (dst, src) in b.chunks_exact_mut(N).zip(&m) {
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
