//! Deterministic random numbers and the direction samplers built on them.
//!
//! Every sample owns a stream seeded from `(seed, pixel, sample, stream)`, so an image does
//! not depend on tile order or thread count.

use glam::Vec3;
use std::f32::consts::PI;

/// PCG32 (O'Neill, XSH-RR output): small state, good statistics, fast.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// SplitMix64 finaliser: spreads nearby inputs (pixel i, i + 1) over the whole state space.
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    /// The stream of `(seed, pixel, sample, stream)`; distinct tuples give independent streams.
    pub fn new(seed: u64, pixel: u64, sample: u32, stream: u32) -> Rng {
        let a = splitmix(seed ^ splitmix(pixel));
        let b = splitmix(a ^ ((u64::from(sample) << 32) | u64::from(stream)));
        let mut rng = Rng {
            state: 0,
            inc: (splitmix(b ^ 0x5851_f42d_4c95_7f2d) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(b);
        rng.next_u32();
        rng
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1): 24 random mantissa bits, so never exactly 1.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

/// Right-handed orthonormal basis `(t, b)` around unit `n` (Duff et al. 2017, branchless).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-weighted direction around unit `n` (pdf cos θ / π): the Lambertian importance sample.
pub fn cosine_hemisphere(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (t, b) = basis(n);
    let z = (1.0 - u1).max(0.0).sqrt();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize_or(n)
}

/// Direction in the Phong lobe `cosⁿ α` around unit `axis` (pdf normalised over the lobe).
pub fn phong_lobe(axis: Vec3, exponent: f32, u1: f32, u2: f32) -> Vec3 {
    let cos_a = u1.powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    let (t, b) = basis(axis);
    (t * (sin_a * phi.cos()) + b * (sin_a * phi.sin()) + axis * cos_a).normalize_or(axis)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let mut a = Rng::new(7, 100, 3, 0);
        let mut b = Rng::new(7, 100, 3, 0);
        let mut c = Rng::new(7, 101, 3, 0);
        let xs: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        let ys: Vec<u32> = (0..8).map(|_| b.next_u32()).collect();
        let zs: Vec<u32> = (0..8).map(|_| c.next_u32()).collect();
        assert_eq!(xs, ys);
        assert_ne!(xs, zs);
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Rng::new(1, 2, 3, 4);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = r.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += f64::from(x);
        }
        assert!((sum / f64::from(n) - 0.5).abs() < 0.01);
    }

    #[test]
    fn basis_is_orthonormal_even_at_poles() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ] {
            let (t, b) = basis(n);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5 && t.dot(b).abs() < 1e-5);
        }
    }

    #[test]
    fn samples_stay_in_their_hemisphere() {
        let mut r = Rng::new(0, 0, 0, 0);
        let n = Vec3::new(0.0, 1.0, 0.0);
        let mut mean_cos = 0.0;
        for _ in 0..10_000 {
            let d = cosine_hemisphere(n, r.next_f32(), r.next_f32());
            assert!(d.dot(n) >= 0.0 && (d.length() - 1.0).abs() < 1e-4);
            mean_cos += d.dot(n) / 10_000.0;
            let g = phong_lobe(n, 100.0, r.next_f32(), r.next_f32());
            assert!(g.dot(n) > 0.8);
        }
        // E[cos θ] under a cosine-weighted density is 2/3.
        assert!((mean_cos - 2.0 / 3.0).abs() < 0.02, "{mean_cos}");
    }
}
