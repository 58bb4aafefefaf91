//! The geometry of reflection-space IBR (Cabral, Olano, Nemec 1999): the
//! geodesic sphere of source view directions (an icosahedron, subdivided
//! as a knob), the spherical triangle holding a view and its spherical
//! barycentric weights (areas by spherical excess, Girard's theorem), each
//! map's camera frame `T` and the sphere-map functions `g_normal` and
//! `g_mirror` with their inverses.

use glam::{Mat3, Vec2, Vec3};
use std::f32::consts::PI;

/// View directions (unit) and the outward-wound spherical triangles
/// between them.
#[derive(Clone, Debug)]
pub struct Geodesic {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<[usize; 3]>,
}

/// Where a view falls: the three source maps and their weights (sum 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewBlend {
    pub sources: [usize; 3],
    pub weights: [f32; 3],
}

impl Geodesic {
    /// The icosahedron (12 vertices, 20 faces) with every face split into
    /// four `level` times, new vertices pushed onto the unit sphere.
    pub fn new(level: u32) -> Self {
        let mut g = icosahedron();
        for _ in 0..level {
            g = g.subdivided();
        }
        g
    }

    fn subdivided(&self) -> Self {
        let mut vertices = self.vertices.clone();
        let mut midpoints = std::collections::HashMap::new();
        let mut mid = |a: usize, b: usize, vertices: &mut Vec<Vec3>| -> usize {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push((vertices[a] + vertices[b]).normalize());
                vertices.len() - 1
            })
        };
        let mut faces = Vec::with_capacity(self.faces.len() * 4);
        for &[a, b, c] in &self.faces {
            let ab = mid(a, b, &mut vertices);
            let bc = mid(b, c, &mut vertices);
            let ca = mid(c, a, &mut vertices);
            faces.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        Self { vertices, faces }
    }

    /// How far `v` lies inside face `f`: the smallest of its signed sines
    /// to the three edge planes (≥ 0 inside or on the border).
    fn inside(&self, f: usize, v: Vec3) -> f32 {
        let [a, b, c] = self.faces[f].map(|i| self.vertices[i]);
        let side = |p: Vec3, q: Vec3| p.cross(q).normalize_or_zero().dot(v);
        side(a, b).min(side(b, c)).min(side(c, a))
    }

    /// The faces holding unit `v` (on a shared edge or vertex, several).
    pub fn containing(&self, v: Vec3) -> Vec<usize> {
        (0..self.faces.len())
            .filter(|&f| self.inside(f, v) >= -1e-6)
            .collect()
    }

    /// The face holding `view` (any non-zero direction; the one it lies
    /// deepest inside) and its three spherical barycentric weights.
    pub fn blend(&self, view: Vec3) -> ViewBlend {
        let v = view.normalize_or(Vec3::Z);
        let face = (0..self.faces.len())
            .max_by(|&a, &b| self.inside(a, v).total_cmp(&self.inside(b, v)))
            .unwrap_or(0);
        let sources = self.faces[face];
        let corners = sources.map(|i| self.vertices[i]);
        ViewBlend {
            sources,
            weights: barycentric(corners, v),
        }
    }
}

/// The 12 unit vertices `(0, ±1, ±φ)` and cyclic permutations, and the 20
/// faces (vertex triples at the edge length), wound counter-clockwise seen
/// from outside.
fn icosahedron() -> Geodesic {
    let phi = (1.0 + 5f32.sqrt()) / 2.0;
    let mut vertices = Vec::new();
    for s1 in [-1.0, 1.0] {
        for s2 in [-1.0, 1.0] {
            vertices.push(Vec3::new(0.0, s1, s2 * phi).normalize());
            vertices.push(Vec3::new(s1, s2 * phi, 0.0).normalize());
            vertices.push(Vec3::new(s2 * phi, 0.0, s1).normalize());
        }
    }
    let edge = (0..12)
        .flat_map(|j| (j + 1..12).map(move |k| (j, k)))
        .map(|(j, k)| vertices[j].distance(vertices[k]))
        .fold(f32::INFINITY, f32::min);
    let near = |a: usize, b: usize| (vertices[a].distance(vertices[b]) - edge).abs() < 1e-4;
    let mut faces = Vec::new();
    for a in 0..12 {
        for b in a + 1..12 {
            for c in b + 1..12 {
                if near(a, b) && near(b, c) && near(c, a) {
                    let outward = (vertices[b] - vertices[a])
                        .cross(vertices[c] - vertices[a])
                        .dot(vertices[a]);
                    faces.push(if outward > 0.0 { [a, b, c] } else { [a, c, b] });
                }
            }
        }
    }
    Geodesic { vertices, faces }
}

/// Area of the spherical triangle `abc` on the unit sphere by its
/// spherical excess (Girard): the sum of its angles minus π; 0 when two
/// corners coincide.
pub fn spherical_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    // The angle at `p` between the great circles towards `q` and `r`.
    let angle = |p: Vec3, q: Vec3, r: Vec3| -> Option<f32> {
        let (u, w) = (p.cross(q), p.cross(r));
        if u.length_squared() < 1e-14 || w.length_squared() < 1e-14 {
            return None;
        }
        Some(u.normalize().dot(w.normalize()).clamp(-1.0, 1.0).acos())
    };
    match (angle(a, b, c), angle(b, c, a), angle(c, a, b)) {
        (Some(x), Some(y), Some(z)) => (x + y + z - PI).max(0.0),
        _ => 0.0,
    }
}

/// The spherical barycentric weights of unit `v` in triangle `corners`:
/// each corner's weight is the area of the sub-triangle opposite it over
/// the sum of the three (so they sum to 1; 1 at the corner itself).
pub fn barycentric(corners: [Vec3; 3], v: Vec3) -> [f32; 3] {
    let [a, b, c] = corners;
    let areas = [
        spherical_area(v, b, c),
        spherical_area(a, v, c),
        spherical_area(a, b, v),
    ];
    let sum: f32 = areas.iter().sum();
    if sum.is_nan() || sum <= 1e-12 {
        // `v` on a corner to within float precision: that corner alone.
        let nearest = (0..3)
            .max_by(|&i, &j| corners[i].dot(v).total_cmp(&corners[j].dot(v)))
            .unwrap_or(0);
        let mut w = [0.0; 3];
        w[nearest] = 1.0;
        return w;
    }
    areas.map(|x| x / sum)
}

/// The camera frame of a map seen from direction `view` (from the
/// reflector towards the eye): columns x right, y up, z = `view`, so
/// `frame * local = world` (the paper's `T`). World up is +Y; straight up
/// or down, +Z stands in for it.
pub fn view_frame(view: Vec3) -> Mat3 {
    let z = view.normalize_or(Vec3::Z);
    let up = if z.cross(Vec3::Y).length_squared() < 1e-8 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let x = up.cross(z).normalize();
    let y = z.cross(x);
    Mat3::from_cols(x, y, z)
}

/// `g_normal`: the normal (local frame) at sphere-map point `p` ∈ [0,1]²
/// (None outside the disk).
pub fn g_normal(p: Vec2) -> Option<Vec3> {
    let xy = 2.0 * p - Vec2::ONE;
    let rr = xy.length_squared();
    (rr <= 1.0).then(|| Vec3::new(xy.x, xy.y, (1.0 - rr).max(0.0).sqrt()))
}

/// `g_mirror`: the mirror reflection of the view `(0, 0, 1)` at `p`.
pub fn g_mirror(p: Vec2) -> Option<Vec3> {
    let n = g_normal(p)?;
    Some(Vec3::new(
        2.0 * n.x * n.z,
        2.0 * n.y * n.z,
        2.0 * n.z * n.z - 1.0,
    ))
}

/// `g_normal⁻¹`: the sphere-map point of unit normal `n`.
pub fn g_normal_inv(n: Vec3) -> Vec2 {
    Vec2::new(n.x, n.y) * 0.5 + Vec2::splat(0.5)
}

/// `g_mirror⁻¹`: the sphere-map point whose mirror reflection is unit `r`
/// (the half vector of `r` and the view); the rim for `r = (0, 0, −1)`.
pub fn g_mirror_inv(r: Vec3) -> Vec2 {
    let h = (r + Vec3::Z).normalize_or(Vec3::X);
    g_normal_inv(h)
}

/// The paper's warp `p_d = g⁻¹ ∘ T_d⁻¹ ∘ T_s ∘ g(p_s)` written the way the
/// disk is drawn: from a destination point `p_d` to the source point that
/// reflects in the same world direction (None outside the disk).
pub fn warp_to_source(p_d: Vec2, dest: Mat3, source: Mat3) -> Option<Vec2> {
    let r_d = g_mirror(p_d)?;
    Some(g_mirror_inv(source.transpose() * (dest * r_d)))
}

/// The warp for lobes centred on the normal (a diffuse reflector): from a
/// destination point to the source point with the same world normal (None
/// outside the disk or where the source view sees the normal edge-on or
/// from behind).
pub fn warp_normal_to_source(p_d: Vec2, dest: Mat3, source: Mat3) -> Option<Vec2> {
    let n_s = source.transpose() * (dest * g_normal(p_d)?);
    (n_s.z > 0.0).then(|| g_normal_inv(n_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_warp_keeps_the_world_normal() {
        let (a, b) = (Vec3::new(0.3, 0.2, 1.0), Vec3::new(-0.2, 0.4, 0.9));
        let (fa, fb) = (view_frame(a), view_frame(b));
        let p_d = Vec2::new(0.55, 0.42);
        let p_s = warp_normal_to_source(p_d, fa, fb).expect("seen from both");
        let (n_d, n_s) = (g_normal(p_d).expect("in"), g_normal(p_s).expect("in"));
        assert!((fa * n_d - fb * n_s).length() < 1e-5);
        // A normal the source sees from behind has no source point.
        let behind = view_frame(-a);
        assert!(warp_normal_to_source(Vec2::splat(0.5), fa, behind).is_none());
    }

    /// Directions spread over the sphere (a Fibonacci lattice, jittered off
    /// any special symmetry).
    fn directions(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let phi = i as f32 * 2.399_963 + 0.123;
                let s = (1.0 - z * z).sqrt();
                Vec3::new(s * phi.cos(), z, s * phi.sin())
            })
            .collect()
    }

    #[test]
    fn icosahedron_has_12_unit_vertices_and_20_outward_faces() {
        let g = Geodesic::new(0);
        assert_eq!(g.vertices.len(), 12);
        assert_eq!(g.faces.len(), 20);
        for v in &g.vertices {
            assert!((v.length() - 1.0).abs() < 1e-6, "{v}");
        }
        let area: f32 = g
            .faces
            .iter()
            .map(|f| spherical_area(g.vertices[f[0]], g.vertices[f[1]], g.vertices[f[2]]))
            .sum();
        assert!((area - 4.0 * PI).abs() < 1e-4, "faces cover {area} sr");
        let g1 = Geodesic::new(1);
        assert_eq!((g1.vertices.len(), g1.faces.len()), (42, 80));
    }

    #[test]
    fn every_direction_falls_in_exactly_one_triangle() {
        for level in [0, 1] {
            let g = Geodesic::new(level);
            for v in directions(2000) {
                let holding = g.containing(v);
                assert_eq!(holding.len(), 1, "level {level}: {v} in {holding:?}");
                assert_eq!(g.blend(v).sources, g.faces[holding[0]]);
            }
        }
    }

    #[test]
    fn weights_sum_to_one_are_one_at_a_vertex_and_never_negative() {
        let g = Geodesic::new(0);
        for v in directions(500) {
            let b = g.blend(v);
            let sum: f32 = b.weights.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5, "{v}: {:?}", b.weights);
            assert!(b.weights.iter().all(|&w| w >= 0.0), "{:?}", b.weights);
            // Linear precision is not promised, but the weights must
            // reproduce the view roughly (a ≤ 0.2 rad error on this mesh).
            let mix: Vec3 = (0..3)
                .map(|i| g.vertices[b.sources[i]] * b.weights[i])
                .sum();
            assert!(mix.normalize().angle_between(v) < 0.2, "{v}: {mix}");
        }
        for (i, &v) in g.vertices.iter().enumerate() {
            let b = g.blend(v);
            let k = b.sources.iter().position(|&s| s == i).expect("a corner");
            assert!((b.weights[k] - 1.0).abs() < 1e-5, "{:?}", b.weights);
        }
        // The centre of a face weighs its corners equally.
        let f = g.faces[3];
        let c = (g.vertices[f[0]] + g.vertices[f[1]] + g.vertices[f[2]]).normalize();
        let w = g.blend(c).weights;
        assert!(w.iter().all(|&x| (x - 1.0 / 3.0).abs() < 1e-4), "{w:?}");
    }

    #[test]
    fn sphere_map_functions_invert_each_other() {
        for &(s, t) in &[(0.5, 0.5), (0.7, 0.2), (0.1, 0.55), (0.93, 0.6)] {
            let p = Vec2::new(s, t);
            let n = g_normal(p).expect("inside");
            assert!((g_normal_inv(n) - p).length() < 1e-5);
            let r = g_mirror(p).expect("inside");
            assert!((r.length() - 1.0).abs() < 1e-5);
            // r is the mirror image of the view (0, 0, 1) about n.
            let expected = 2.0 * n.z * n - Vec3::Z;
            assert!((r - expected).length() < 1e-5);
            assert!((g_mirror_inv(r) - p).length() < 1e-4, "{p} {r}");
        }
        assert!(g_normal(Vec2::new(0.0, 0.0)).is_none());
        // The centre reflects straight back; the rim reflects away.
        let centre = g_mirror(Vec2::splat(0.5)).expect("inside");
        assert!((centre - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn warp_between_frames_keeps_the_world_reflection() {
        let (a, b) = (Vec3::new(0.3, 0.2, 1.0), Vec3::new(-0.4, 0.5, 0.8));
        let (fa, fb) = (view_frame(a), view_frame(b));
        assert!((fa.col(2) - a.normalize()).length() < 1e-6);
        assert!((fa.transpose() * fa - Mat3::IDENTITY).abs_diff_eq(Mat3::ZERO, 1e-5));
        let p_d = Vec2::new(0.6, 0.45);
        let p_s = warp_to_source(p_d, fa, fb).expect("inside");
        let world_d = fa * g_mirror(p_d).expect("inside");
        let world_s = fb * g_mirror(p_s).expect("inside");
        assert!((world_d - world_s).length() < 1e-3, "{world_d} {world_s}");
        // Same frame: the identity.
        let same = warp_to_source(p_d, fa, fa).expect("inside");
        assert!((same - p_d).length() < 1e-4);
        // Straight up has a frame too.
        let up = view_frame(Vec3::Y);
        assert!(up.col(0).is_finite() && (up.col(2) - Vec3::Y).length() < 1e-6);
    }
}
