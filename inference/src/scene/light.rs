//! Lights: the rectangular area light of every shipped scene, and the
//! optional directional and point lights (`[[directional_lights]]`,
//! `[[point_lights]]`) that the relighting work moves around.

use glam::{Vec2, Vec3};

use super::mesh::Mesh;

/// One-sided emitter: the parallelogram `center ± edge_u/2 ± edge_v/2`, emitting
/// `radiance` (W·sr⁻¹·m⁻² per channel) on the side of `normal() = edge_u × edge_v`.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    pub name: String,
    pub center: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    pub radiance: Vec3,
}

impl AreaLight {
    pub fn normal(&self) -> Vec3 {
        self.edge_u.cross(self.edge_v).normalize_or_zero()
    }

    pub fn area(&self) -> f32 {
        self.edge_u.cross(self.edge_v).length()
    }

    /// The rectangle as two triangles facing the emitting side; UVs span [0, 1]².
    pub fn mesh(&self) -> Mesh {
        Mesh {
            positions: self.corners().to_vec(),
            normals: vec![self.normal(); 4],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    /// Corners counter-clockwise seen from the emitting side.
    pub fn corners(&self) -> [Vec3; 4] {
        let (hu, hv) = (0.5 * self.edge_u, 0.5 * self.edge_v);
        [
            self.center - hu - hv,
            self.center + hu - hv,
            self.center + hu + hv,
            self.center - hu + hv,
        ]
    }
}

/// Parallel light from direction `to_light` (unit, pointing *toward* the light),
/// delivering `irradiance` (W·m⁻² per channel) to a surface facing it.
///
/// The room is a closed box, so a directional light reaches inside the way sun
/// reaches a room with open walls: the room's own box (objects `floor`, `walls`,
/// `ceiling`, see [`ROOM_OBJECTS`]) does not shadow it, every other object does.
/// Each room face is lit only on the side facing the light (the floor from above,
/// a wall from inside when the light comes from beyond the opposite wall).
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalLight {
    pub name: String,
    pub to_light: Vec3,
    pub irradiance: Vec3,
}

/// An isotropic point light at `position` with `intensity` (W·sr⁻¹ per channel):
/// a surface at distance d facing it receives `intensity / d²`. Everything shadows it.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    pub name: String,
    pub position: Vec3,
    pub intensity: Vec3,
}

/// The room's box objects, transparent to directional light.
pub const ROOM_OBJECTS: [&str; 3] = ["floor", "walls", "ceiling"];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceiling_light_faces_down_and_winds_ccw() {
        let l = AreaLight {
            name: "l".into(),
            center: Vec3::new(0.0, 3.9, 0.0),
            edge_u: Vec3::new(1.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 0.5),
            radiance: Vec3::ONE,
        };
        assert_eq!(l.normal(), -Vec3::Y);
        assert!((l.area() - 0.5).abs() < 1e-6);
        let c = l.corners();
        let n = (c[1] - c[0]).cross(c[2] - c[0]);
        assert!(n.normalize().abs_diff_eq(l.normal(), 1e-6));
        assert!(((c[0] + c[2]) * 0.5).abs_diff_eq(l.center, 1e-6));
        let m = l.mesh();
        assert!((m.area() - l.area()).abs() < 1e-6);
        let [a, b, d] = m.triangle(1);
        assert!(
            (b - a)
                .cross(d - a)
                .normalize()
                .abs_diff_eq(l.normal(), 1e-6)
        );
    }
}
