//! The room: an axis-aligned box seen from inside, as floor, walls and ceiling meshes.

use glam::{Vec2, Vec3};

use super::mesh::Mesh;

/// An axis-aligned quad `origin + s·a + t·b`, s, t ∈ [0, 1], facing `a × b`,
/// with UVs from world position: `uv_axes` picks the two world axes, divided by `tile`.
fn quad(mesh: &mut Mesh, origin: Vec3, a: Vec3, b: Vec3, uv_axes: [usize; 2], tile: f32) {
    let base = mesh.positions.len() as u32;
    let normal = a.cross(b).normalize_or_zero();
    for p in [origin, origin + a, origin + a + b, origin + b] {
        mesh.positions.push(p);
        mesh.normals.push(normal);
        mesh.uvs
            .push(Vec2::new(p[uv_axes[0]], p[uv_axes[1]]) / tile);
    }
    // Counter-clockwise seen from the side `normal` points to.
    mesh.indices
        .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
}

/// Floor (y = min.y, facing up); UV = (x, z) / tile.
pub fn floor(min: Vec3, max: Vec3, tile: f32) -> Mesh {
    let d = max - min;
    let mut m = Mesh::default();
    quad(&mut m, min, Vec3::Z * d.z, Vec3::X * d.x, [0, 2], tile);
    m
}

/// Ceiling (y = max.y, facing down); UV = (x, z) / tile.
pub fn ceiling(min: Vec3, max: Vec3, tile: f32) -> Mesh {
    let d = max - min;
    let mut m = Mesh::default();
    let o = Vec3::new(min.x, max.y, min.z);
    quad(&mut m, o, Vec3::X * d.x, Vec3::Z * d.z, [0, 2], tile);
    m
}

/// The four walls, facing inward; UV = (horizontal world coordinate, y) / tile.
pub fn walls(min: Vec3, max: Vec3, tile: f32) -> Mesh {
    let d = max - min;
    let (x, y, z) = (Vec3::X * d.x, Vec3::Y * d.y, Vec3::Z * d.z);
    let mut m = Mesh::default();
    quad(&mut m, min, y, z, [2, 1], tile); // x = min.x, faces +x
    quad(&mut m, Vec3::new(max.x, min.y, min.z), z, y, [2, 1], tile); // faces −x
    quad(&mut m, min, x, y, [0, 1], tile); // z = min.z, faces +z
    quad(&mut m, Vec3::new(min.x, min.y, max.z), y, x, [0, 1], tile); // faces −z
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn room_faces_point_inward_with_matching_winding() {
        let (min, max) = (Vec3::new(-4.0, 0.0, -4.0), Vec3::new(4.0, 4.0, 4.0));
        let centre = (min + max) * 0.5;
        for mesh in [
            floor(min, max, 1.0),
            ceiling(min, max, 1.0),
            walls(min, max, 1.0),
        ] {
            for t in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(t);
                let n = (b - a).cross(c - a).normalize();
                let vertex_normal = mesh.normals[mesh.indices[3 * t] as usize];
                assert!(n.abs_diff_eq(vertex_normal, 1e-6));
                assert!(
                    n.dot(centre - a) > 0.0,
                    "face {t} must face the room centre"
                );
            }
            let (lo, hi) = mesh.bounds();
            assert!(lo.cmpge(min).all() && hi.cmple(max).all());
        }
        assert!((walls(min, max, 1.0).area() - 4.0 * 32.0).abs() < 1e-4);
    }

    #[test]
    fn uvs_are_world_position_over_tile() {
        let m = floor(Vec3::new(-4.0, 0.0, -2.0), Vec3::new(4.0, 3.0, 2.0), 0.5);
        for (p, uv) in m.positions.iter().zip(&m.uvs) {
            assert_eq!(*uv, Vec2::new(p.x, p.z) / 0.5);
        }
    }
}
