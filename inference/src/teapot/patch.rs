//! Evaluation of one bicubic Bézier patch: position and both partial derivatives.

use glam::Vec3;

use super::data::{PATCHES, POINTS};

/// Newell's data is z-up; ours is y-up: (x, y, z) ↦ (x, z, −y), a proper rotation about x,
/// so orientation and handedness are preserved and the spout still points to +x.
pub fn to_y_up([x, y, z]: [f32; 3]) -> Vec3 {
    Vec3::new(x, z, -y)
}

/// A bicubic patch; `cp[row][col]`, rows follow parameter `u`, columns parameter `v`.
#[derive(Clone, Copy, Debug)]
pub struct Patch {
    pub cp: [[Vec3; 4]; 4],
}

/// A surface sample: position and partial derivatives ∂P/∂u, ∂P/∂v.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub position: Vec3,
    pub du: Vec3,
    pub dv: Vec3,
}

impl Patch {
    /// Patch `index` (0..32) of the teapot, in y-up coordinates (original units).
    pub fn teapot(index: usize) -> Option<Patch> {
        let ids = PATCHES.get(index)?;
        let cp = std::array::from_fn(|r| {
            std::array::from_fn(|c| to_y_up(POINTS[ids[4 * r + c] as usize]))
        });
        Some(Patch { cp })
    }

    pub fn eval(&self, u: f32, v: f32) -> Sample {
        let (bu, dbu) = (bernstein(u), bernstein_derivative(u));
        let (bv, dbv) = (bernstein(v), bernstein_derivative(v));
        let mut s = Sample {
            position: Vec3::ZERO,
            du: Vec3::ZERO,
            dv: Vec3::ZERO,
        };
        for r in 0..4 {
            for c in 0..4 {
                let p = self.cp[r][c];
                s.position += bu[r] * bv[c] * p;
                s.du += dbu[r] * bv[c] * p;
                s.dv += bu[r] * dbv[c] * p;
            }
        }
        s
    }

    /// Unit surface normal ∂P/∂v × ∂P/∂u (outward for Newell's patch orientation).
    ///
    /// Where a patch edge collapses to a point (lid and bottom poles) the cross product
    /// vanishes; the normal there is the limit from inside the patch, found by stepping
    /// a little toward the patch interior. `None` if even that is degenerate.
    pub fn normal(&self, u: f32, v: f32) -> Option<Vec3> {
        const NUDGE: f32 = 1e-3;
        let inward = |t: f32| if t < 0.5 { t + NUDGE } else { t - NUDGE };
        [
            (u, v),
            (inward(u), v),
            (u, inward(v)),
            (inward(u), inward(v)),
        ]
        .into_iter()
        .find_map(|(u, v)| {
            let s = self.eval(u, v);
            let n = s.dv.cross(s.du);
            // Relative to the larger derivative: along a collapsed edge one derivative
            // is rounding noise, and so is its cross product with the other.
            let scale = s.du.length_squared().max(s.dv.length_squared());
            (n.length() > 1e-6 * scale && scale > 0.0)
                .then(|| n.normalize_or_zero())
                .filter(|n| n.is_finite() && *n != Vec3::ZERO)
        })
    }
}

fn bernstein(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

fn bernstein_derivative(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * t * s,
        6.0 * t * s - 3.0 * t * t,
        3.0 * t * t,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        let p = Patch::teapot(16).expect("patch"); // spout: nothing axis-aligned, a fair test
        let h = 1e-3;
        for &(u, v) in &[(0.3f32, 0.6f32), (0.5, 0.5), (0.9, 0.1)] {
            let s = p.eval(u, v);
            let du = (p.eval(u + h, v).position - p.eval(u - h, v).position) / (2.0 * h);
            let dv = (p.eval(u, v + h).position - p.eval(u, v - h).position) / (2.0 * h);
            assert!(s.du.abs_diff_eq(du, 1e-2), "{:?} vs {du:?}", s.du);
            assert!(s.dv.abs_diff_eq(dv, 1e-2), "{:?} vs {dv:?}", s.dv);
        }
    }

    #[test]
    fn corners_interpolate_control_points() {
        assert!(Patch::teapot(32).is_none());
        for i in 0..32 {
            let p = Patch::teapot(i).expect("patch");
            assert_eq!(p.eval(0.0, 0.0).position, p.cp[0][0]);
            assert_eq!(p.eval(1.0, 1.0).position, p.cp[3][3]);
        }
    }

    #[test]
    fn pole_normals_are_the_axis() {
        // Lid knob (20..24) has its pole at the top, bottom (28..32) at the origin.
        for i in 20..24 {
            for v in [0.0, 0.3, 1.0] {
                let n = Patch::teapot(i)
                    .expect("patch")
                    .normal(0.0, v)
                    .unwrap_or(Vec3::ZERO);
                assert!(n.dot(Vec3::Y) > 0.999, "lid patch {i} v {v}: {n:?}");
            }
        }
        for i in 28..32 {
            for v in [0.0, 0.3, 1.0] {
                let n = Patch::teapot(i)
                    .expect("patch")
                    .normal(0.0, v)
                    .unwrap_or(Vec3::ZERO);
                assert!(n.dot(-Vec3::Y) > 0.999, "bottom patch {i} v {v}: {n:?}");
            }
        }
    }
}
