//! Schlick's Fresnel approximation: the one formula both the tracer and the runtime use.

use glam::Vec3;

/// `F0 + (1 − F0)(1 − cos θ)⁵`, with `cos θ` clamped to [0, 1] (NaN counts as grazing),
/// so the result is finite and within [F0, 1] for every input in [0, 1].
pub fn schlick_fresnel(f0: Vec3, cos_theta: f32) -> Vec3 {
    let c = if cos_theta.is_nan() {
        0.0
    } else {
        cos_theta.clamp(0.0, 1.0)
    };
    let m = 1.0 - c;
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOLD: Vec3 = Vec3::new(1.0, 0.71, 0.29);

    #[test]
    fn normal_incidence_is_f0() {
        assert_eq!(schlick_fresnel(GOLD, 1.0), GOLD);
        assert_eq!(schlick_fresnel(Vec3::splat(0.04), 2.0), Vec3::splat(0.04));
    }

    #[test]
    fn grazing_is_one() {
        assert_eq!(schlick_fresnel(GOLD, 0.0), Vec3::ONE);
        assert_eq!(schlick_fresnel(GOLD, -0.5), Vec3::ONE);
        // Exactly 90° computed from an angle: cos is ~-4e-8, still clamped to 1.
        let c = std::f32::consts::FRAC_PI_2.cos();
        assert!(schlick_fresnel(GOLD, c).abs_diff_eq(Vec3::ONE, 1e-6));
        assert_eq!(schlick_fresnel(GOLD, f32::NAN), Vec3::ONE);
    }

    #[test]
    fn monotone_and_bounded() {
        let f0 = Vec3::splat(0.04);
        let mut prev = Vec3::ONE;
        for i in 0..=100 {
            let f = schlick_fresnel(f0, i as f32 / 100.0);
            assert!(f.is_finite() && f.cmple(prev).all() && f.cmpge(f0).all());
            prev = f;
        }
    }

    proptest::proptest! {
        #[test]
        fn finite_and_between_f0_and_one(
            f0 in proptest::array::uniform3(0.0f32..=1.0),
            cos in proptest::num::f32::ANY,
        ) {
            let f0 = Vec3::from_array(f0);
            let f = schlick_fresnel(f0, cos);
            proptest::prop_assert!(f.is_finite());
            proptest::prop_assert!(f.cmpge(f0).all() && f.cmple(Vec3::ONE).all());
        }
    }
}
