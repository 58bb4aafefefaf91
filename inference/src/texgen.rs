//! CPU texgen: per vertex, reflect the eye ray off the normal and produce
//! the cube-map lookup vector plus cos θ for the Fresnel LUT (PEM paper §4:
//! the GPU only interpolates what the CPU computed per vertex).
//!
//! This module is the sphere-at-infinity case (the lookup is the reflected
//! direction itself); finite EM geometry (box, ellipsoid) intersects the ray
//! first and returns `hit − EM origin`.

use glam::Vec3A;

/// One vertex's texgen output: `[lookup.x, lookup.y, lookup.z, cos θ]`,
/// with cos θ = n·(eye − p)/|eye − p| clamped to [0, 1].
pub type TexgenVertex = [f32; 4];

/// Reflected direction of the view ray `view` (from the eye, unit) off the
/// unit normal `n`, and the clamped cosine between `n` and the eye.
///
/// A zero or non-finite normal carries no orientation; the vertex is then
/// treated as facing the eye (reflection straight back, cos θ = 1) so the
/// output stays finite.
#[inline]
pub fn reflect_view(view: Vec3A, normal: Vec3A) -> (Vec3A, f32) {
    let n = normal.try_normalize().unwrap_or(-view);
    let d = view.dot(n);
    (view - 2.0 * d * n, (-d).clamp(0.0, 1.0))
}

/// Sphere-at-infinity texgen for every vertex into `out` (same length as
/// `positions`). Positions and normals are in world space.
pub fn sphere_at_infinity(
    eye: glam::Vec3,
    positions: &[glam::Vec3],
    normals: &[glam::Vec3],
    out: &mut [TexgenVertex],
) {
    let eye = Vec3A::from(eye);
    for ((p, n), o) in positions.iter().zip(normals).zip(out.iter_mut()) {
        let view = (Vec3A::from(*p) - eye)
            .try_normalize()
            .unwrap_or(Vec3A::NEG_Z);
        let (r, cos) = reflect_view(view, Vec3A::from(*n));
        *o = [r.x, r.y, r.z, cos];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn head_on_reflects_back_with_cos_one() {
        let mut out = [[0.0; 4]];
        sphere_at_infinity(
            Vec3::new(0.0, 0.0, 5.0),
            &[Vec3::ZERO],
            &[Vec3::Z],
            &mut out,
        );
        assert_eq!(out[0], [0.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn forty_five_degrees_reflects_sideways() {
        let mut out = [[0.0; 4]];
        // Eye up the +y axis looking down at a plane tilted 45° about z.
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        sphere_at_infinity(Vec3::new(0.0, 10.0, 0.0), &[Vec3::ZERO], &[n], &mut out);
        let [x, y, z, cos] = out[0];
        assert!(
            (x - 1.0).abs() < 1e-6 && y.abs() < 1e-6 && z.abs() < 1e-6,
            "{:?}",
            out[0]
        );
        assert!((cos - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
    }

    #[test]
    fn grazing_and_back_facing_clamp_cos_to_zero() {
        let mut out = [[0.0; 4]; 2];
        let eye = Vec3::new(0.0, 0.0, 5.0);
        sphere_at_infinity(eye, &[Vec3::ZERO; 2], &[Vec3::X, Vec3::NEG_Z], &mut out);
        assert_eq!(out[0][3], 0.0, "exactly 90°");
        assert_eq!(out[1][3], 0.0, "facing away");
    }

    #[test]
    fn zero_normal_and_eye_on_vertex_stay_finite() {
        let mut out = [[0.0; 4]; 3];
        let eye = Vec3::new(1.0, 2.0, 3.0);
        sphere_at_infinity(
            eye,
            &[Vec3::ZERO, eye, Vec3::ONE],
            &[Vec3::ZERO, Vec3::Y, Vec3::splat(f32::NAN)],
            &mut out,
        );
        for v in out {
            assert!(v.iter().all(|c| c.is_finite()), "{v:?}");
        }
        assert!(
            (out[0][3] - 1.0).abs() < 1e-6,
            "zero normal faces the eye: {:?}",
            out[0]
        );
    }
}
