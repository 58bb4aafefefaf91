//! Cube-map faces in Vulkan's order (+X, −X, +Y, −Y, +Z, −Z = array layers
//! 0..6) and the projection that renders a face so that sampling the cube
//! with a direction returns what was rendered in that direction.
//!
//! Built from the specification's face-selection table ("Cube Map Face
//! Selection"): for major axis `ma` the face coordinates are
//! `s = (sc/|ma| + 1)/2`, `t = (tc/|ma| + 1)/2`, with t growing down the
//! image rows, which is Vulkan's NDC y. So clip = (sc, tc, z(|ma|), |ma|).

use glam::{Mat4, Vec3};

pub const FACE_COUNT: u32 = 6;

/// For each face, the world axes giving (sc, tc, ma) as in the spec table.
const FACE_AXES: [[Vec3; 3]; 6] = [
    [Vec3::NEG_Z, Vec3::NEG_Y, Vec3::X],     // +X: sc = -rz, tc = -ry
    [Vec3::Z, Vec3::NEG_Y, Vec3::NEG_X],     // -X: sc = +rz, tc = -ry
    [Vec3::X, Vec3::Z, Vec3::Y],             // +Y: sc = +rx, tc = +rz
    [Vec3::X, Vec3::NEG_Z, Vec3::NEG_Y],     // -Y: sc = +rx, tc = -rz
    [Vec3::X, Vec3::NEG_Y, Vec3::Z],         // +Z: sc = +rx, tc = -ry
    [Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z], // -Z: sc = -rx, tc = -ry
];

/// View-projection rendering face `face` (0..6) of a cube centred at
/// `origin`, depth in [0, 1] between `near` and `far` along the major axis.
pub fn face_view_proj(face: u32, origin: Vec3, near: f32, far: f32) -> Mat4 {
    let [sc, tc, ma] = FACE_AXES[(face % FACE_COUNT) as usize];
    let a = far / (far - near);
    let b = -far * near / (far - near);
    // Rows of the projection acting on the direction d = p − origin.
    let rows = Mat4::from_cols(
        sc.extend(0.0),
        tc.extend(0.0),
        (ma * a).extend(b),
        ma.extend(0.0),
    )
    .transpose();
    rows * Mat4::from_translation(-origin)
}

/// The (sc, tc, ma) axes of face `face` (0..6): the direction through face
/// point (s, t) is `(2s − 1)·sc + (2t − 1)·tc + ma`.
pub fn face_axes(face: u32) -> [Vec3; 3] {
    FACE_AXES[(face % FACE_COUNT) as usize]
}

/// The face a direction selects and its (s, t) in [0, 1]², per the spec.
pub fn face_coords(d: Vec3) -> (u32, f32, f32) {
    let a = d.abs();
    let face = if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if d.y >= 0.0 { 2 } else { 3 }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    };
    let [sc, tc, ma] = FACE_AXES[face as usize];
    let m = d.dot(ma);
    (
        face,
        0.5 * (d.dot(sc) / m + 1.0),
        0.5 * (d.dot(tc) / m + 1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_axes_give_the_direction_face_coords_reads_back() {
        for face in 0..FACE_COUNT {
            for (s, t) in [(0.5, 0.5), (0.1, 0.8), (0.93, 0.02)] {
                let [sc, tc, ma] = face_axes(face);
                let d = (2.0 * s - 1.0) * sc + (2.0 * t - 1.0) * tc + ma;
                let (f, s2, t2) = face_coords(d);
                assert_eq!(f, face);
                assert!(
                    (s2 - s).abs() < 1e-6 && (t2 - t).abs() < 1e-6,
                    "{face} {s} {t}"
                );
            }
        }
    }
    use glam::Vec4;

    #[test]
    fn face_projection_agrees_with_spec_face_selection() {
        let origin = Vec3::new(0.3, 1.0, -0.2);
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..1000 {
            let d = Vec3::new(next(), next(), next());
            if d.length() < 1e-3 {
                continue;
            }
            let (face, s, t) = face_coords(d);
            let clip =
                face_view_proj(face, origin, 0.05, 50.0) * Vec4::from((origin + d * 3.0, 1.0));
            let ndc = clip.truncate() / clip.w;
            assert!(clip.w > 0.0);
            assert!((ndc.x - (2.0 * s - 1.0)).abs() < 1e-4, "face {face} d {d}");
            assert!((ndc.y - (2.0 * t - 1.0)).abs() < 1e-4, "face {face} d {d}");
            assert!((0.0..=1.0).contains(&ndc.z));
        }
    }

    #[test]
    fn face_centres_land_mid_image() {
        for face in 0..FACE_COUNT {
            let ma = FACE_AXES[face as usize][2];
            let clip = face_view_proj(face, Vec3::ZERO, 0.1, 10.0) * ma.extend(1.0);
            assert!(clip.x.abs() < 1e-6 && clip.y.abs() < 1e-6 && clip.w == 1.0);
        }
    }
}
