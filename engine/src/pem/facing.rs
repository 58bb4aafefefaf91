//! The triangles of a reflector that a view can show: back faces culled on
//! the CPU, beside texgen, so that texgen runs only on the vertices those
//! triangles use and the device's one-threaded vertex and set-up stage
//! (lavapipe's) never sees the other half of the mesh. The pipelines still
//! cull back faces themselves: this only drops triangles they would drop
//! anyway, so the frame is the same bit for bit.

use glam::Vec2;

/// A reflector's triangles as its draws order them (convex-hull triangles
/// first), built once.
pub struct FacingMesh {
    indices: Vec<u32>,
    hull_index_count: u32,
    vertices: usize,
}

/// What one view keeps: the hull-sorted indices of the triangles it may
/// draw (hull ones first) and which vertices they use.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Facing {
    pub indices: Vec<u32>,
    pub hull_index_count: u32,
    pub used: Vec<bool>,
}

impl FacingMesh {
    /// `indices` of a mesh of `vertices` vertices, the hull's first
    /// `hull_index_count`.
    pub fn new(vertices: usize, indices: Vec<u32>, hull_index_count: u32) -> Self {
        Self {
            indices,
            hull_index_count,
            vertices,
        }
    }

    /// The triangles a frame with its vertices at `pixels` (screen
    /// positions, y down, from [`crate::passes::bands::project`]) may draw
    /// with counter-clockwise front faces: all but those surely seen from
    /// behind. It keeps every triangle where no screen position holds
    /// (None: a vertex at or behind the eye, which the rasterizer clips)
    /// and every one with an index out of range (the draw, not this,
    /// refuses a bad mesh).
    pub fn facing(&self, pixels: Option<&[Vec2]>) -> Facing {
        let mut used = vec![false; self.vertices];
        let mut indices = Vec::with_capacity(self.indices.len() / 2 + 3);
        let mut hull_index_count = 0;
        for (i, t) in self.indices.chunks_exact(3).enumerate() {
            if 3 * i as u32 == self.hull_index_count {
                hull_index_count = indices.len() as u32;
            }
            let on_screen = |k: u32| pixels.and_then(|p| p.get(k as usize));
            let back = match (on_screen(t[0]), on_screen(t[1]), on_screen(t[2])) {
                (Some(&a), Some(&b), Some(&c)) => surely_back(a, b, c),
                _ => false,
            };
            if !back {
                indices.extend_from_slice(t);
                for &k in t {
                    if let Some(u) = used.get_mut(k as usize) {
                        *u = true;
                    }
                }
            }
        }
        if self.indices.len() as u32 <= self.hull_index_count {
            hull_index_count = indices.len() as u32;
        }
        Facing {
            indices,
            hull_index_count,
            used,
        }
    }
}

/// Whether the triangle at screen positions `a`, `b`, `c` (pixels, y
/// down) faces away however the rasterizer snaps them. lavapipe decides
/// facing from the sign of the area after snapping each coordinate to
/// 1/256 pixel (±1/512), which moves twice the area by at most 1/512 of
/// the triangle's L1 perimeter (plus a square term); twice that margin,
/// and ~10⁻³ px² for the rounding of this projection, leaves every
/// triangle a hair from edge-on to the rasterizer.
fn surely_back(a: Vec2, b: Vec2, c: Vec2) -> bool {
    let twice_area = (b - a).perp_dot(c - a);
    let l1 =
        (b - a).abs().element_sum() + (c - b).abs().element_sum() + (a - c).abs().element_sum();
    // NaN compares false: kept.
    twice_area > l1 / 256.0 + 1e-3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::bands::project;
    use glam::{DMat4, DVec2, Mat4, Vec3};

    const SIZE: (u32, u32) = (640, 480);

    fn view_proj(eye: Vec3, target: Vec3) -> Mat4 {
        let proj = glam::camera::rh::proj::vulkan::perspective(0.7, 640.0 / 480.0, 0.05, 30.0);
        proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y)
    }

    fn facing_from(mesh: &FacingMesh, positions: &[Vec3], eye: Vec3, target: Vec3) -> Facing {
        let mut pixels = Vec::new();
        let on_screen = project(view_proj(eye, target), positions, SIZE, &mut pixels);
        mesh.facing(on_screen.map(|()| pixels.as_slice()))
    }

    /// Two triangles of the square in z = 0, one counter-clockwise seen
    /// from +z and one seen from −z, the first on the hull.
    fn square() -> (Vec<Vec3>, FacingMesh) {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let mesh = FacingMesh::new(positions.len(), vec![0, 1, 2, 0, 3, 2], 3);
        (positions, mesh)
    }

    #[test]
    fn keeps_the_triangles_facing_the_eye_and_their_vertices() {
        let (p, mesh) = square();
        let centre = Vec3::new(0.5, 0.5, 0.0);
        let front = facing_from(&mesh, &p, Vec3::new(0.5, 0.5, 3.0), centre);
        assert_eq!(front.indices, [0, 1, 2]);
        assert_eq!(front.hull_index_count, 3);
        assert_eq!(front.used, [true, true, true, false]);
        let back = facing_from(&mesh, &p, Vec3::new(0.5, 0.5, -3.0), centre);
        assert_eq!(back.indices, [0, 3, 2]);
        assert_eq!(back.hull_index_count, 0);
        assert_eq!(back.used, [true, false, true, true]);
    }

    #[test]
    fn keeps_everything_it_cannot_place_on_screen_or_call_back_facing() {
        let (p, mesh) = square();
        // Edge-on: both kept.
        let edge_on = facing_from(
            &mesh,
            &p,
            Vec3::new(3.0, 0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
        );
        assert_eq!(edge_on.indices.len(), 6);
        // A vertex behind the eye: no screen positions, every triangle.
        let behind = facing_from(
            &mesh,
            &p,
            Vec3::new(0.5, 0.5, -0.5),
            Vec3::new(0.5, 0.5, -3.0),
        );
        assert_eq!(behind.indices.len(), 6);
        assert_eq!(behind.used, [true; 4]);
        // A line and a triangle naming a missing vertex: kept.
        let odd = FacingMesh::new(4, vec![0, 1, 1, 0, 1, 9], 0);
        let kept = facing_from(&odd, &p, Vec3::new(0.5, 0.5, -3.0), Vec3::ZERO);
        assert_eq!(kept.indices, [0, 1, 1, 0, 1, 9]);
        assert_eq!(kept.used, [true, true, false, false]);
    }

    #[test]
    fn drops_only_triangles_the_rasterizer_sees_from_behind() {
        let scene = inference::scene::Scene::load("teapot").expect("built-in scene");
        let teapot = scene.objects.iter().find(|o| o.name == "teapot");
        let mesh = &teapot.expect("the teapot").mesh;
        let p = &mesh.positions;
        let facing = FacingMesh::new(p.len(), mesh.indices.clone(), 0);
        let (mut dropped, mut total) = (0usize, 0usize);
        // Eyes around, above, below and close to the teapot.
        for k in 0..48 {
            let (az, el) = (k as f32 * 0.61, (k % 7) as f32 * 0.45 - 1.3);
            let r = [0.45, 1.5, 4.0][k % 3];
            let target = Vec3::new(0.0, 0.25, 0.0);
            let eye = target + r * Vec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos());
            let kept = facing_from(&facing, p, eye, target);
            let kept: std::collections::HashSet<&[u32]> = kept.indices.chunks(3).collect();
            // In f64: where each vertex lands on screen.
            let vp: DMat4 = view_proj(eye, target).as_dmat4();
            let px = |k: u32| {
                let c = vp * p[k as usize].as_dvec3().extend(1.0);
                (c.truncate().truncate() / c.w * 0.5 + 0.5) * DVec2::new(640.0, 480.0)
            };
            for t in mesh.indices.chunks_exact(3).filter(|t| !kept.contains(*t)) {
                dropped += 1;
                let (a, b, c) = (px(t[0]), px(t[1]), px(t[2]));
                let l1 = (b - a).abs().element_sum()
                    + (c - b).abs().element_sum()
                    + (a - c).abs().element_sum();
                // Back-facing even with every coordinate snapped by ±1/512.
                let twice_area = (b - a).perp_dot(c - a);
                assert!(twice_area > l1 / 512.0 + 1e-5, "eye {eye}: {t:?}");
                // And facing away in the world, as the mesh's winding says.
                let (wa, wb, wc) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
                assert!(
                    (wb - wa).cross(wc - wa).dot(eye - wa) < 0.0,
                    "eye {eye}: {t:?}"
                );
            }
            total += mesh.indices.len() / 3;
        }
        // The test can fail: about half of every view is dropped.
        assert!(dropped * 10 > total * 4, "{dropped} of {total} dropped");
        assert!(dropped * 10 < total * 6, "{dropped} of {total} dropped");
    }
}
