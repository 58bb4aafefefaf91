//! Real spherical harmonics, as in the appendix of Wong, Or and Fu, "Real-time
//! relighting of compressed panoramas" (seed 001, `shared/seeds/001_…`):
//!
//! ```text
//! Y_lm(θ, φ) = N_lm Q_lm(cos θ) cos(mφ)          m > 0
//!            = N_l0 Q_l0(cos θ) / √2             m = 0
//!            = N_l|m| Q_l|m|(cos θ) sin(|m|φ)    m < 0
//! N_lm = √((2l + 1)/(2π) · (l − |m|)!/(l + |m|)!)
//! Q_00 = 1,  Q_mm = (1 − 2m) √(1 − x²) Q_(m−1)(m−1),  Q_(m+1)m = (2m + 1) x Q_mm,
//! Q_lm = ((2l − 1) x Q_(l−1)m − (l + m − 1) Q_(l−2)m) / (l − m)   otherwise.
//! ```
//!
//! Directions are world vectors, y up: `cos θ = d.y`, `sin θ cos φ = d.x`,
//! `sin θ sin φ = d.z`. Coefficient `i = l(l + 1) + m`, so the first `k = (L + 1)²`
//! cover bands `l ≤ L` (k = 9, 16, 25: L = 2, 3, 4).
//!
//! [`eval_appendix`] follows the appendix literally (angles, square root, cos mφ);
//! [`eval`] is the same basis without trigonometry, the form the GPU pass uses:
//! `Q_lm(x) = sin^m θ · P_lm(x)` with `P` the same recurrence minus the `√(1 − x²)`
//! factor, and `sin^m θ (cos mφ + i sin mφ) = (d.x + i d.z)^m`.

use glam::Vec3;

/// Most coefficients supported (bands l ≤ 4).
pub const MAX_K: usize = 25;
/// The SH orders the relighting tables report.
pub const ORDERS: [usize; 3] = [9, 16, 25];

/// Band count `L + 1` for `k = (L + 1)²` coefficients, if `k` is a square ≤ [`MAX_K`].
pub fn bands(k: usize) -> Option<usize> {
    let b = (k as f64).sqrt().round() as usize;
    (b * b == k && (1..=5).contains(&b)).then_some(b)
}

/// `N_lm` of the appendix (|m| ≤ l).
pub fn norm(l: usize, m: usize) -> f64 {
    let fact = |n: usize| (1..=n).map(|x| x as f64).product::<f64>();
    ((2 * l + 1) as f64 / (2.0 * std::f64::consts::PI) * fact(l - m) / fact(l + m)).sqrt()
}

/// `Q_lm(x)` by the appendix's recurrence (0 ≤ m ≤ l).
pub fn legendre(l: usize, m: usize, x: f64) -> f64 {
    let s = (1.0 - x * x).max(0.0).sqrt();
    let mut qmm = 1.0;
    for j in 1..=m {
        qmm *= (1.0 - 2.0 * j as f64) * s;
    }
    if l == m {
        return qmm;
    }
    let mut prev = qmm;
    let mut cur = (2 * m + 1) as f64 * x * qmm;
    for ll in m + 2..=l {
        let next = ((2 * ll - 1) as f64 * x * cur - (ll + m - 1) as f64 * prev) / (ll - m) as f64;
        prev = cur;
        cur = next;
    }
    cur
}

/// `Y_i(d)` for `i < out.len()` (≤ [`MAX_K`]), literally per the appendix.
pub fn eval_appendix(d: Vec3, out: &mut [f32]) {
    let d = d.as_dvec3().normalize_or(glam::DVec3::Y);
    let (x, phi) = (d.y.clamp(-1.0, 1.0), d.z.atan2(d.x));
    for (i, y) in out.iter_mut().enumerate().take(MAX_K) {
        let l = (i as f64).sqrt() as usize;
        let m = i as i64 - (l * l + l) as i64;
        let am = m.unsigned_abs() as usize;
        let base = norm(l, am) * legendre(l, am, x);
        *y = match m.signum() {
            1 => base * (am as f64 * phi).cos(),
            0 => base / std::f64::consts::SQRT_2,
            _ => base * (am as f64 * phi).sin(),
        } as f32;
    }
}

/// `Y_i(d)` for `i < out.len()` (≤ [`MAX_K`]) without trigonometry; `d` need not be
/// unit (it is normalised; zero gives the pole +y).
pub fn eval(d: Vec3, out: &mut [f32]) {
    let d = d.normalize_or(Vec3::Y);
    let k = out.len().min(MAX_K);
    let lmax = (k as f32).sqrt().ceil() as usize;
    // (d.x + i d.z)^m for m = 0..lmax.
    let mut re = [1.0f32; 5];
    let mut im = [0.0f32; 5];
    for m in 1..lmax.min(5) {
        re[m] = re[m - 1] * d.x - im[m - 1] * d.z;
        im[m] = re[m - 1] * d.z + im[m - 1] * d.x;
    }
    for m in 0..lmax.min(5) {
        // P_mm, then up the recurrence in l.
        let mut pmm = 1.0f32;
        for j in 1..=m {
            pmm *= 1.0 - 2.0 * j as f32;
        }
        let (mut prev, mut cur) = (0.0f32, pmm);
        for l in m..lmax.min(5) {
            if l == m + 1 {
                (prev, cur) = (cur, (2 * m + 1) as f32 * d.y * pmm);
            } else if l > m + 1 {
                let next =
                    ((2 * l - 1) as f32 * d.y * cur - (l + m - 1) as f32 * prev) / (l - m) as f32;
                (prev, cur) = (cur, next);
            }
            let n = norm(l, m) as f32 * cur;
            let center = l * l + l;
            if m == 0 {
                if center < k {
                    out[center] = n * std::f32::consts::FRAC_1_SQRT_2;
                }
            } else {
                if center + m < k {
                    out[center + m] = n * re[m];
                }
                if center - m < k {
                    out[center - m] = n * im[m];
                }
            }
        }
    }
}

/// `Σ_i c_i Y_i(d)` over `c.len()` coefficients: the relit value of one texel.
pub fn reconstruct(c: &[f32], d: Vec3) -> f32 {
    let mut y = [0.0f32; MAX_K];
    let k = c.len().min(MAX_K);
    eval(d, &mut y[..k]);
    c.iter().zip(&y[..k]).map(|(a, b)| a * b).sum()
}
