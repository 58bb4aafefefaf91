//! Which triangles of a mesh lie on its convex hull (PEM paper §4: polygons
//! on the reflector's convex hull use the distant EM only — a reflected ray
//! leaving them cannot hit the reflector again).
//!
//! # Criterion
//!
//! Triangle `abc` with unit normal `n = (b − a) × (c − a) / |…|` (its front
//! side is the counter-clockwise one, as the renderer's front face) is **on
//! the hull** iff no vertex of the mesh lies in front of its plane by more
//! than the tolerance:
//!
//! `max_v n·(v − a) ≤ tol`, over every finite vertex some triangle uses.
//!
//! The plane is then a supporting plane of the hull and the triangle faces
//! out of it, so no reflected ray from its front side can reach the mesh.
//! This is exact (in f64) up to `tol`; it is conservative wherever it can
//! be: a triangle lying on the hull but wound inward, a degenerate
//! triangle (no plane: collinear or coincident corners, non-finite corners,
//! see [`is_degenerate`]) and a triangle with an index out of range all get
//! `false` — "may self-reflect" only costs the local EM, while a wrong
//! `true` would drop self-reflections.
//!
//! # Tolerance
//!
//! `tol = RELATIVE_TOLERANCE × d + 8 ε₃₂ × m`, with `d` the diagonal of the
//! used vertices' bounding box (the mesh size), `m` their largest absolute
//! coordinate and ε₃₂ the f32 machine epsilon: the first term makes
//! coplanar tessellations (a box face split into many triangles) count as
//! on the hull, the second absorbs the rounding of f32 coordinates far from
//! the origin. [`hull_triangles_with_tolerance`] takes another relative
//! tolerance.
//!
//! # Speed
//!
//! The vertices go into a bounding-box tree (median splits, 16 points per
//! leaf). Per triangle, nodes whose box lies wholly behind the plane
//! (`n·centre + |n|·half-extent ≤ n·a + tol`) are pruned and the child
//! reaching further along `n` is opened first, so a triangle off the hull
//! finds a vertex in front after a short descent towards the extreme point
//! along its normal (early exit), and a triangle on the hull only opens the
//! few nodes that touch its supporting plane. Triangles run in parallel
//! (rayon).

use crate::scene::Mesh;
use crate::scene::mesh::is_degenerate;
use rayon::prelude::*;

/// Default tolerance, relative to the mesh's bounding-box diagonal.
pub const RELATIVE_TOLERANCE: f64 = 1e-5;

const LEAF_SIZE: usize = 16;

/// One flag per triangle of `mesh` (`mesh.triangle_count()` of them): true
/// when the triangle lies on the mesh's convex hull and faces out of it,
/// with the default tolerance (see the module documentation).
pub fn hull_triangles(mesh: &Mesh) -> Vec<bool> {
    hull_triangles_with_tolerance(mesh, RELATIVE_TOLERANCE)
}

/// As [`hull_triangles`], but a triangle is on the hull only if no vertex
/// of `others` lies in front of it either: the reflectors that share the
/// mesh's local layer (lid and body, `Scene::local_group`), which a ray
/// leaving the triangle could hit.
pub fn hull_triangles_among(mesh: &Mesh, others: &[&Mesh]) -> Vec<bool> {
    hull_triangles_of(mesh, others, RELATIVE_TOLERANCE)
}

/// As [`hull_triangles`] with `relative_tolerance` × the bounding-box
/// diagonal in place of [`RELATIVE_TOLERANCE`] (negative or NaN counts as
/// 0; the f32 rounding term is always added).
pub fn hull_triangles_with_tolerance(mesh: &Mesh, relative_tolerance: f64) -> Vec<bool> {
    hull_triangles_of(mesh, &[], relative_tolerance)
}

/// The corners of triangle `t` when its indices are in range.
fn corners(mesh: &Mesh, t: usize) -> Option<[usize; 3]> {
    let i = mesh.indices.get(3 * t..3 * t + 3)?;
    let c = [i[0] as usize, i[1] as usize, i[2] as usize];
    c.iter().all(|&k| k < mesh.positions.len()).then_some(c)
}

/// Every finite vertex a triangle of `mesh` uses, once, in f64.
fn used_points(mesh: &Mesh) -> Vec<[f64; 3]> {
    let mut used = vec![false; mesh.positions.len()];
    for t in 0..mesh.triangle_count() {
        if let Some(c) = corners(mesh, t) {
            c.iter().for_each(|&k| used[k] = true);
        }
    }
    mesh.positions
        .iter()
        .zip(&used)
        .filter(|(p, u)| **u && p.is_finite())
        .map(|(p, _)| p.as_dvec3().to_array())
        .collect()
}

fn hull_triangles_of(mesh: &Mesh, others: &[&Mesh], relative_tolerance: f64) -> Vec<bool> {
    let n_triangles = mesh.triangle_count();
    let mut points = used_points(mesh);
    others.iter().for_each(|m| points.extend(used_points(m)));
    let tree = Tree::new(points);
    let tol = tree.tolerance(relative_tolerance);
    (0..n_triangles)
        .into_par_iter()
        .map_init(Vec::new, |stack, t| {
            let Some(c) = corners(mesh, t) else {
                return false;
            };
            let [a, b, c] = c.map(|k| mesh.positions[k]);
            if is_degenerate([a, b, c]) {
                return false;
            }
            let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
            let Some(n) = (b - a).cross(c - a).try_normalize() else {
                return false;
            };
            !tree.any_in_front(n.to_array(), n.dot(a) + tol, stack)
        })
        .collect()
}

struct Node {
    /// Box centre and half extent.
    centre: [f64; 3],
    half: [f64; 3],
    /// Leaf: `points[start..end]`; inner: children `start` and `end`.
    start: usize,
    end: usize,
    leaf: bool,
}

/// A bounding-box tree over points (the root is node 0 when non-empty).
struct Tree {
    points: Vec<[f64; 3]>,
    nodes: Vec<Node>,
    /// Largest absolute coordinate, for the rounding slack.
    max_abs: f64,
    diagonal: f64,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Tree {
    fn new(mut points: Vec<[f64; 3]>) -> Tree {
        let mut nodes = Vec::new();
        if !points.is_empty() {
            let len = points.len();
            build(&mut points, 0, len, &mut nodes);
        }
        let max_abs = points.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let diagonal = nodes
            .first()
            .map_or(0.0, |root: &Node| 2.0 * dot(root.half, root.half).sqrt());
        Tree {
            points,
            nodes,
            max_abs,
            diagonal,
        }
    }

    fn tolerance(&self, relative: f64) -> f64 {
        let relative = if relative > 0.0 { relative } else { 0.0 };
        relative * self.diagonal + 8.0 * f64::from(f32::EPSILON) * self.max_abs
    }

    /// Whether some point `p` has `n·p > threshold`.
    fn any_in_front(&self, n: [f64; 3], threshold: f64, stack: &mut Vec<usize>) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let abs_n = n.map(f64::abs);
        // Box bounds are computed in floating point too: prune only when
        // the bound is below the threshold by more than its rounding.
        let slack = 1e-12 * (self.max_abs + self.diagonal);
        let reach = |node: &Node| dot(n, node.centre) + dot(abs_n, node.half) + slack;
        stack.clear();
        stack.push(0);
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            if reach(node) <= threshold {
                continue;
            }
            if node.leaf {
                if self.points[node.start..node.end]
                    .iter()
                    .any(|&p| dot(n, p) > threshold)
                {
                    return true;
                }
            } else {
                let (l, r) = (node.start, node.end);
                // Open the child reaching further along n first (pushed last).
                if reach(&self.nodes[l]) > reach(&self.nodes[r]) {
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
                }
            }
        }
        false
    }
}

/// Builds the node for `points[start..end]` (non-empty) and its subtree;
/// returns its index.
fn build(points: &mut [[f64; 3]], start: usize, end: usize, nodes: &mut Vec<Node>) -> usize {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &points[start..end] {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let index = nodes.len();
    nodes.push(Node {
        centre: [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])),
        half: [0, 1, 2].map(|k| 0.5 * (hi[k] - lo[k])),
        start,
        end,
        leaf: true,
    });
    if end - start <= LEAF_SIZE {
        return index;
    }
    let extent = [0, 1, 2].map(|k| hi[k] - lo[k]);
    let axis = (0..3)
        .max_by(|&a, &b| extent[a].total_cmp(&extent[b]))
        .unwrap_or(0);
    let mid = start + (end - start) / 2;
    points[start..end].select_nth_unstable_by(mid - start, |a, b| a[axis].total_cmp(&b[axis]));
    let left = build(points, start, mid, nodes);
    let right = build(points, mid, end, nodes);
    let node = &mut nodes[index];
    (node.start, node.end, node.leaf) = (left, right, false);
    index
}

#[cfg(test)]
#[path = "hull_tests.rs"]
mod tests;
