//! Chart coordinates of a diffuse object: every surface point gets its own
//! place, in metres, so one view-independent texture can hold its light.
//!
//! An object made of a few planes whose triangles share no vertex across
//! planes (the room's floor, ceiling and four walls) gets one chart per
//! plane: coordinates along two orthonormal in-plane axes, measured from
//! the chart's lowest corner. Any other mesh keeps its own UVs as one chart,
//! scaled so a unit of chart coordinates is about a metre on the surface
//! (tiled UVs would then make several places share texels: such meshes
//! should carry unique UVs).

use crate::scene::Mesh;
use glam::{DVec3, Vec2, Vec3};

/// Most planes an object may have before its own UVs are used instead.
pub const MAX_PLANES: usize = 16;
/// Planes closer than this (cosine of the normals' angle, and offsets
/// relative to the mesh's diagonal) are one.
const SAME_NORMAL: f64 = 1.0 - 1e-6;
const SAME_OFFSET: f64 = 1e-5;

/// How an object's vertices map to chart coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Charts {
    /// Chart of each vertex (every triangle's vertices share one chart).
    pub vertex_chart: Vec<u32>,
    /// Chart coordinates of each vertex, metres from the chart's low corner.
    pub coords: Vec<Vec2>,
    /// Per chart: its extent, the largest coordinates of its vertices.
    pub extents: Vec<Vec2>,
    /// One chart per plane (true) or the mesh's own UVs (false).
    pub planar: bool,
}

impl Charts {
    pub fn count(&self) -> usize {
        self.extents.len()
    }

    /// The chart of triangle `t` of `mesh`.
    pub fn triangle_chart(&self, mesh: &Mesh, t: usize) -> u32 {
        self.vertex_chart[mesh.indices[3 * t] as usize]
    }

    /// Surface directions (3D, per metre of chart coordinates) of triangle
    /// `t`: `p(c + δ) ≈ p(c) + δ.x·T_u + δ.y·T_v`. None when its chart
    /// coordinates are degenerate.
    pub fn tangents(&self, mesh: &Mesh, t: usize) -> Option<(Vec3, Vec3)> {
        let i = &mesh.indices[3 * t..3 * t + 3];
        let p = |k: usize| mesh.positions[i[k] as usize].as_dvec3();
        let c = |k: usize| self.coords[i[k] as usize].as_dvec2();
        let (e1, e2) = (p(1) - p(0), p(2) - p(0));
        let (d1, d2) = (c(1) - c(0), c(2) - c(0));
        let det = d1.x * d2.y - d1.y * d2.x;
        if det.abs() < 1e-12 {
            return None;
        }
        // [E1 E2] = [T_u T_v] · [D1 D2]  ⇒  [T_u T_v] = [E1 E2] · [D1 D2]⁻¹.
        let t_u = (e1 * d2.y - e2 * d1.y) / det;
        let t_v = (e2 * d1.x - e1 * d2.x) / det;
        Some((t_u.as_vec3(), t_v.as_vec3()))
    }
}

/// The charts of `mesh`: one per plane when it is a few disjoint planes,
/// else its own UVs.
pub fn charts(mesh: &Mesh) -> Charts {
    planar_charts(mesh).unwrap_or_else(|| own_uvs(mesh))
}

struct Plane {
    normal: DVec3,
    offset: f64,
}

fn planar_charts(mesh: &Mesh) -> Option<Charts> {
    let (lo, hi) = mesh.bounds();
    let tolerance = SAME_OFFSET * f64::from((hi - lo).length()).max(1e-6);
    let mut planes: Vec<Plane> = Vec::new();
    let mut vertex_chart = vec![u32::MAX; mesh.positions.len()];
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(t).map(Vec3::as_dvec3);
        let normal = (b - a).cross(c - a).try_normalize()?;
        let offset = normal.dot(a);
        let chart = match planes.iter().position(|p| {
            p.normal.dot(normal) >= SAME_NORMAL && (p.offset - offset).abs() <= tolerance
        }) {
            Some(i) => i,
            None if planes.len() < MAX_PLANES => {
                planes.push(Plane { normal, offset });
                planes.len() - 1
            }
            None => return None,
        } as u32;
        for &v in &mesh.indices[3 * t..3 * t + 3] {
            let slot = &mut vertex_chart[v as usize];
            if *slot != u32::MAX && *slot != chart {
                return None; // a vertex shared by two planes has no single place
            }
            *slot = chart;
        }
    }
    let axes: Vec<(DVec3, DVec3)> = planes.iter().map(|p| in_plane_axes(p.normal)).collect();
    let coords: Vec<Vec2> = mesh
        .positions
        .iter()
        .zip(&vertex_chart)
        .map(|(p, &c)| match axes.get(c as usize) {
            Some((u, v)) => Vec2::new(u.dot(p.as_dvec3()) as f32, v.dot(p.as_dvec3()) as f32),
            None => Vec2::ZERO, // a vertex no triangle uses
        })
        .collect();
    Some(from_low_corner(vertex_chart, coords, planes.len(), true))
}

/// Two orthonormal axes in the plane of unit `normal` (world axes for
/// axis-aligned planes: the floor's are −x and +z, a wall's its horizontal
/// and +y).
fn in_plane_axes(normal: DVec3) -> (DVec3, DVec3) {
    let helper = if normal.y.abs() < 0.9 {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let u = helper.cross(normal).normalize();
    (u, normal.cross(u))
}

fn own_uvs(mesh: &Mesh) -> Charts {
    let (mut area, mut uv_area) = (0.0f64, 0.0f64);
    for t in 0..mesh.triangle_count() {
        let i = &mesh.indices[3 * t..3 * t + 3];
        area += f64::from(crate::scene::mesh::triangle_area(mesh.triangle(t)));
        let uv = |k: usize| mesh.uvs.get(i[k] as usize).copied().unwrap_or_default();
        let (d1, d2) = (uv(1) - uv(0), uv(2) - uv(0));
        uv_area += 0.5 * f64::from(d1.perp_dot(d2)).abs();
    }
    let scale = if uv_area > 0.0 && area > 0.0 {
        (area / uv_area).sqrt() as f32
    } else {
        1.0
    };
    let coords = (0..mesh.positions.len())
        .map(|v| mesh.uvs.get(v).copied().unwrap_or_default() * scale)
        .collect();
    from_low_corner(vec![0; mesh.positions.len()], coords, 1, false)
}

/// Shifts every chart's coordinates so its lowest corner is (0, 0).
fn from_low_corner(
    vertex_chart: Vec<u32>,
    mut coords: Vec<Vec2>,
    count: usize,
    planar: bool,
) -> Charts {
    let mut lo = vec![Vec2::splat(f32::INFINITY); count];
    let mut hi = vec![Vec2::ZERO; count];
    for (c, &k) in coords.iter().zip(&vertex_chart) {
        if let Some(l) = lo.get_mut(k as usize) {
            *l = l.min(*c);
        }
    }
    for (c, &k) in coords.iter_mut().zip(&vertex_chart) {
        if let (Some(l), Some(h)) = (lo.get(k as usize), hi.get_mut(k as usize)) {
            *c -= *l;
            *h = h.max(*c);
        }
    }
    let vertex_chart = vertex_chart
        .into_iter()
        .map(|k| k.min(count as u32 - 1))
        .collect();
    Charts {
        vertex_chart,
        coords,
        extents: hi,
        planar,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::room;

    #[test]
    fn the_walls_are_four_charts_in_metres() {
        let (min, max) = (Vec3::new(-4.0, 0.0, -4.0), Vec3::new(4.0, 4.0, 4.0));
        let walls = room::walls(min, max, 1.0);
        let c = charts(&walls);
        assert!(c.planar);
        assert_eq!(c.count(), 4);
        for e in &c.extents {
            // Each wall is 8 m along and 4 m up, whichever way its axes run.
            let (a, b) = (e.x.max(e.y), e.x.min(e.y));
            assert!((a - 8.0).abs() < 1e-5 && (b - 4.0).abs() < 1e-5, "{e:?}");
        }
        for t in 0..walls.triangle_count() {
            let (tu, tv) = c.tangents(&walls, t).expect("tangents");
            assert!((tu.length() - 1.0).abs() < 1e-5 && (tv.length() - 1.0).abs() < 1e-5);
            assert!(tu.dot(tv).abs() < 1e-5);
        }
        let floor = charts(&room::floor(min, max, 1.0));
        assert_eq!(floor.count(), 1);
        assert_eq!(floor.extents[0], Vec2::new(8.0, 8.0));
    }

    #[test]
    fn a_curved_mesh_keeps_its_own_uvs_scaled_to_metres() {
        let mesh = crate::teapot::tessellate(4, crate::teapot::TeapotPart::Whole)
            .expect("teapot")
            .mesh;
        let c = charts(&mesh);
        assert!(!c.planar);
        assert_eq!(c.count(), 1);
        assert!(c.vertex_chart.iter().all(|&k| k == 0));
        assert!(
            c.coords
                .iter()
                .all(|p| p.is_finite() && p.min_element() >= 0.0)
        );
    }

    #[test]
    fn planes_sharing_a_vertex_fall_back_to_own_uvs() {
        // Two triangles folded along a shared edge.
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE],
            indices: vec![0, 1, 2, 0, 3, 1],
        };
        assert!(!charts(&mesh).planar);
    }
}
