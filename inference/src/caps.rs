//! Caps over a mesh's openings: each loop of boundary edges (an edge one
//! triangle uses, corners welded by position) closed by a fan from the
//! loop's centroid. A closed reflector's parts leave such openings between
//! them (the gap between a teapot's lid and body, the spout's tip); the
//! rasterizer culls the inside faces seen through them and showed the room
//! where the tracer sees the dark inside. Drawn black with depth, the caps
//! give the inside back for a few hundred triangles (the teapot: 400),
//! where drawing every back face cost ~2 ms a frame on lavapipe.

use crate::scene::Mesh;
use crate::scene::mesh::triangle_area;
use glam::Vec3;
use std::collections::HashMap;

type Key = (i64, i64, i64);

/// The largest cap, as a share of the mesh's own area, that closes an
/// opening. Smaller loops are gaps in a solid (the teapot's largest, the
/// body's rim under the lid, is 11.7%; 13.4% for the body alone), whose inside
/// the tracer sees dark after a few mirror bounces; a larger loop outlines
/// an open surface (a mirror pane: 100%, a bowl: 50%), whose inside faces
/// the eye and which a black cap would hide or z-fight. The share is of the
/// whole mesh, not of the connected part a loop bounds: the teapot's lid,
/// spout and handle are parts of their own, open where they meet the body,
/// and their loops are its openings. A pane inside a larger model is
/// therefore capped; give it an object of its own.
pub const MAX_OPENING_SHARE: f32 = 0.25;

/// The cap triangles of `mesh`'s boundary loops that close openings (see
/// [`MAX_OPENING_SHARE`]), as an unindexed-style mesh (three fresh corners
/// per triangle, normals and UVs zero); empty for a closed mesh. Chains
/// that do not close (non-manifold corners) are left open.
pub fn boundary_caps(mesh: &Mesh) -> Mesh {
    let surface: f32 = (0..mesh.triangle_count())
        .map(|t| triangle_area(mesh.triangle(t)))
        .sum();
    let mut caps = Mesh::default();
    for ring in &boundary_loops(mesh) {
        let c = ring.iter().copied().sum::<Vec3>() / ring.len() as f32;
        let fan = (0..ring.len()).map(|i| triangle_area([c, ring[i], ring[(i + 1) % ring.len()]]));
        if fan.sum::<f32>() > MAX_OPENING_SHARE * surface {
            continue;
        }
        for (i, &a) in ring.iter().enumerate() {
            let b = ring[(i + 1) % ring.len()];
            let base = caps.positions.len() as u32;
            caps.positions.extend([c, a, b]);
            caps.indices.extend([base, base + 1, base + 2]);
        }
    }
    caps.normals = vec![Vec3::ZERO; caps.positions.len()];
    caps.uvs = vec![glam::Vec2::ZERO; caps.positions.len()];
    caps
}

/// The closed loops of boundary edges, each as its corners in order.
pub fn boundary_loops(mesh: &Mesh) -> Vec<Vec<Vec3>> {
    let (lo, hi) = mesh.bounds();
    // Corners closer than a millionth of the mesh's size are one corner:
    // patches meet at equal positions up to rounding, not shared indices.
    let cell = ((hi - lo).length() * 1e-6).max(f32::MIN_POSITIVE);
    let key = |p: Vec3| -> Key {
        let q = (p / cell).round();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut uses: HashMap<(Key, Key), u32> = HashMap::new();
    let mut directed = Vec::new();
    for t in 0..mesh.triangle_count() {
        let corners = mesh.triangle(t);
        for k in 0..3 {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            let (ka, kb) = (key(a), key(b));
            if ka == kb {
                continue;
            }
            *uses.entry((ka.min(kb), ka.max(kb))).or_insert(0) += 1;
            directed.push((ka, kb, a));
        }
    }
    let mut next: HashMap<Key, (Key, Vec3)> = HashMap::new();
    for (ka, kb, a) in directed {
        if uses.get(&(ka.min(kb), ka.max(kb))) == Some(&1) {
            next.entry(ka).or_insert((kb, a));
        }
    }
    let mut loops = Vec::new();
    let mut starts: Vec<Key> = next.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        let mut ring = Vec::new();
        let mut at = start;
        while let Some((to, p)) = next.remove(&at) {
            ring.push(p);
            at = to;
        }
        if at == start && ring.len() >= 3 {
            loops.push(ring);
        }
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's faces as triangles, without the faces `skip` names
    /// (0..6: −x, +x, −y, +y, −z, +z).
    fn cube(skip: &[usize]) -> Mesh {
        let faces: [[Vec3; 4]; 6] = [
            [
                Vec3::new(0., 0., 0.),
                Vec3::new(0., 0., 1.),
                Vec3::new(0., 1., 1.),
                Vec3::new(0., 1., 0.),
            ],
            [
                Vec3::new(1., 0., 0.),
                Vec3::new(1., 1., 0.),
                Vec3::new(1., 1., 1.),
                Vec3::new(1., 0., 1.),
            ],
            [
                Vec3::new(0., 0., 0.),
                Vec3::new(1., 0., 0.),
                Vec3::new(1., 0., 1.),
                Vec3::new(0., 0., 1.),
            ],
            [
                Vec3::new(0., 1., 0.),
                Vec3::new(0., 1., 1.),
                Vec3::new(1., 1., 1.),
                Vec3::new(1., 1., 0.),
            ],
            [
                Vec3::new(0., 0., 0.),
                Vec3::new(0., 1., 0.),
                Vec3::new(1., 1., 0.),
                Vec3::new(1., 0., 0.),
            ],
            [
                Vec3::new(0., 0., 1.),
                Vec3::new(1., 0., 1.),
                Vec3::new(1., 1., 1.),
                Vec3::new(0., 1., 1.),
            ],
        ];
        let mut m = Mesh::default();
        for (_, &f) in faces.iter().enumerate().filter(|(i, _)| !skip.contains(i)) {
            push_quad(&mut m, f);
        }
        m
    }

    /// Appends quad `q` (corners counter-clockwise seen from its front) as
    /// two triangles with corners of its own, as patches have: welding
    /// joins them.
    fn push_quad(m: &mut Mesh, q: [Vec3; 4]) {
        let base = m.positions.len() as u32;
        m.positions.extend(q);
        m.normals.extend([Vec3::Y; 4]);
        m.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    #[test]
    fn a_closed_mesh_has_no_caps() {
        assert!(boundary_caps(&cube(&[])).indices.is_empty());
        assert!(boundary_caps(&Mesh::default()).indices.is_empty());
    }

    #[test]
    fn an_open_face_is_capped_over_its_square() {
        let caps = boundary_caps(&cube(&[3]));
        let loops = boundary_loops(&cube(&[3]));
        assert_eq!(loops.len(), 1, "one opening");
        assert_eq!(loops[0].len(), 4, "its four corners");
        assert_eq!(caps.triangle_count(), 4, "a fan of four");
        // The fan lies in the opening's plane and covers its whole area.
        assert!(caps.positions.iter().all(|p| (p.y - 1.0).abs() < 1e-6));
        let area: f32 = (0..caps.triangle_count())
            .map(|t| triangle_area(caps.triangle(t)))
            .sum();
        assert!((area - 1.0).abs() < 1e-5, "{area}");
    }

    #[test]
    fn an_open_surface_is_not_capped() {
        // A mirror pane: its outline is a loop whose cap is the pane itself.
        let mut pane = cube(&[0, 1, 2, 4, 5]);
        assert_eq!(boundary_loops(&pane).len(), 1);
        assert!(boundary_caps(&pane).indices.is_empty(), "pane capped");
        // A bowl (a hemisphere, open at its rim): the rim's disk is half the
        // bowl's area.
        pane = bowl(24, 12);
        assert_eq!(boundary_loops(&pane).len(), 1);
        assert!(boundary_caps(&pane).indices.is_empty(), "bowl capped");
        // The same bowl with its rim drawn in to a narrow neck is a vessel
        // whose opening is small: capped.
        let vessel = bowl(24, 22);
        assert_eq!(boundary_caps(&vessel).triangle_count(), 24);
    }

    /// A unit sphere's cap below latitude `rows` of 24 (0 = the south
    /// pole, 12 = the equator), open at its top ring, as a mesh.
    fn bowl(segments: usize, rows: usize) -> Mesh {
        let point = |i: usize, j: usize| {
            let lat = -std::f32::consts::FRAC_PI_2 + std::f32::consts::PI * j as f32 / 24.0;
            let lon = std::f32::consts::TAU * (i % segments) as f32 / segments as f32;
            Vec3::new(lat.cos() * lon.cos(), lat.sin(), lat.cos() * lon.sin())
        };
        let mut m = Mesh::default();
        for j in 0..rows {
            for i in 0..segments {
                let q = [
                    point(i, j),
                    point(i, j + 1),
                    point(i + 1, j + 1),
                    point(i + 1, j),
                ];
                push_quad(&mut m, q);
            }
        }
        m
    }

    #[test]
    fn two_openings_get_two_caps() {
        assert_eq!(boundary_loops(&cube(&[0, 1])).len(), 2);
    }

    #[test]
    fn the_teapot_closes_its_lid_gap_and_spout() {
        let scene = crate::scene::Scene::load("teapot").expect("teapot");
        let teapot = scene.object("teapot").expect("teapot object");
        let loops = boundary_loops(&teapot.mesh);
        let edges: usize = loops.iter().map(Vec::len).sum();
        // Every boundary edge of the patches lies on a closed loop.
        assert!(loops.len() >= 2, "{} loops", loops.len());
        assert!(edges >= 100, "{edges} boundary edges on loops");
        let caps = boundary_caps(&teapot.mesh);
        assert_eq!(caps.triangle_count(), edges);
        assert!(caps.positions.iter().all(|p| p.is_finite()));
    }
}
