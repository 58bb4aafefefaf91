//! A texture atlas for a mesh's PTM: every surface point its own texels.
//!
//! The generated teapot's own UVs are a cylindrical projection (`teapot::
//! tessellate`): spout, handle and lid share texels with the body behind
//! them, and the triangles across the seam stretch over the whole texture,
//! so a texture on them cannot hold a view's reflection. The atlas is a
//! box projection: charts of edge-connected triangles whose normals face
//! the same of the six axis directions, each projected along that axis,
//! packed on shelves at one texel density with a gutter between charts.
//! Its vertices are the mesh's, repeated where charts meet, so whatever
//! draws the atlas (PTM playback, its probe renders) uses the atlas's own
//! vertices and indices.

use crate::scene::Mesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Gutters around each chart, in finest-level texels, widest first: the
/// widest that keeps at least [`GUTTER_DENSITY`] of the density without
/// one is used (on a small texture a gutter's texels are dear).
const GUTTERS: [u32; 3] = [2, 1, 0];
const GUTTER_DENSITY: f32 = 0.75;

/// A seamed copy of a mesh with atlas coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    /// The mesh vertex each atlas vertex copies.
    pub source: Vec<u32>,
    /// Atlas coordinates in [0, 1]² of each atlas vertex.
    pub uvs: Vec<Vec2>,
    /// The mesh's triangles, in its order, over atlas vertices.
    pub indices: Vec<u32>,
    /// Number of charts (0 when the mesh's own UVs were kept).
    pub charts: u32,
}

impl Atlas {
    /// The atlas as a mesh: positions and normals of the source vertices.
    pub fn mesh(&self, mesh: &Mesh) -> Mesh {
        let at = |i: &u32| *i as usize;
        Mesh {
            positions: self.source.iter().map(|i| mesh.positions[at(i)]).collect(),
            normals: self
                .source
                .iter()
                .map(|i| mesh.normals.get(at(i)).copied().unwrap_or_default())
                .collect(),
            uvs: self.uvs.clone(),
            indices: self.indices.clone(),
        }
    }

    /// The mesh's own UVs, unchanged: what a mesh whose charts cannot fit
    /// the texture (a triangle soup of thousands of charts) keeps.
    fn own_uvs(mesh: &Mesh) -> Self {
        Self {
            source: (0..mesh.positions.len() as u32).collect(),
            uvs: (0..mesh.positions.len())
                .map(|i| mesh.uvs.get(i).copied().unwrap_or_default())
                .collect(),
            indices: mesh.indices.clone(),
            charts: 0,
        }
    }
}

/// The atlas of `mesh` for a `resolution`² texture.
pub fn build(mesh: &Mesh, resolution: u32) -> Atlas {
    let (chart_of, count) = charts(mesh);
    let axes = chart_axes(mesh, &chart_of, count);
    // Chart-local vertices: one per (chart, mesh vertex), in first-use order.
    let mut vertex_of: HashMap<(u32, u32), u32> = HashMap::new();
    let mut source = Vec::new();
    let mut chart_of_vertex = Vec::new();
    let mut indices = Vec::with_capacity(mesh.indices.len());
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let c = chart_of[t];
        for &v in tri {
            let next = source.len() as u32;
            let a = *vertex_of.entry((c, v)).or_insert(next);
            if a == next {
                source.push(v);
                chart_of_vertex.push(c);
            }
            indices.push(a);
        }
    }
    let planar: Vec<Vec2> = source
        .iter()
        .zip(&chart_of_vertex)
        .map(|(&v, &c)| project(mesh.positions[v as usize], axes[c as usize]))
        .collect();
    let mut lo = vec![Vec2::splat(f32::INFINITY); count as usize];
    let mut hi = vec![Vec2::splat(f32::NEG_INFINITY); count as usize];
    for (p, &c) in planar.iter().zip(&chart_of_vertex) {
        lo[c as usize] = lo[c as usize].min(*p);
        hi[c as usize] = hi[c as usize].max(*p);
    }
    let extents: Vec<Vec2> = lo.iter().zip(&hi).map(|(l, h)| *h - *l).collect();
    let packings: Vec<_> = (GUTTERS.iter())
        .filter_map(|&g| densest_packing(&extents, resolution, g).map(|(s, o)| (s, g, o)))
        .collect();
    // None fit (no packing at all): the mesh keeps its own UVs.
    let densest = packings.iter().map(|p| p.0).fold(0.0, f32::max);
    let Some((scale, gutter, origins)) =
        (packings.into_iter()).find(|(s, _, _)| *s >= GUTTER_DENSITY * densest)
    else {
        return Atlas::own_uvs(mesh);
    };
    let r = resolution as f32;
    let uvs = planar
        .iter()
        .zip(&chart_of_vertex)
        .map(|(p, &c)| {
            let c = c as usize;
            (origins[c] + Vec2::splat(gutter as f32) + (*p - lo[c]) * scale) / r
        })
        .collect();
    Atlas {
        source,
        uvs,
        indices,
        charts: count,
    }
}

/// Which of the six axis directions a normal faces most: 2·axis + (negative).
fn facing(n: Vec3) -> u32 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + u32::from(n[axis as usize] < 0.0)
}

/// The chart of each triangle and the number of charts: components of
/// triangles that share an edge and face the same way.
fn charts(mesh: &Mesh) -> (Vec<u32>, u32) {
    let n = mesh.triangle_count();
    let face: Vec<u32> = (0..n)
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            facing((b - a).cross(c - a))
        })
        .collect();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut t: u32) -> u32 {
        while parent[t as usize] != t {
            let up = parent[parent[t as usize] as usize];
            parent[t as usize] = up;
            t = up;
        }
        t
    }
    let mut first_on_edge: HashMap<(u32, u32), u32> = HashMap::new();
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let other = *first_on_edge
                .entry((a.min(b), a.max(b)))
                .or_insert(t as u32);
            if face[other as usize] == face[t] {
                let (ra, rb) = (root(&mut parent, other), root(&mut parent, t as u32));
                parent[ra as usize] = rb;
            }
        }
    }
    let mut index_of_root = HashMap::new();
    let chart_of = (0..n as u32)
        .map(|t| {
            let r = root(&mut parent, t);
            let next = index_of_root.len() as u32;
            *index_of_root.entry(r).or_insert(next)
        })
        .collect();
    (chart_of, index_of_root.len() as u32)
}

/// The axis each chart is projected along (the facing of its first
/// triangle: all of a chart's triangles share it).
fn chart_axes(mesh: &Mesh, chart_of: &[u32], count: u32) -> Vec<usize> {
    let mut axes = vec![0; count as usize];
    for (t, &c) in chart_of.iter().enumerate().rev() {
        let [a, b, d] = mesh.triangle(t);
        axes[c as usize] = (facing((b - a).cross(d - a)) / 2) as usize;
    }
    axes
}

/// `p` projected along `axis` onto the plane of the other two.
fn project(p: Vec3, axis: usize) -> Vec2 {
    match axis {
        0 => Vec2::new(p.z, p.y),
        1 => Vec2::new(p.x, p.z),
        _ => Vec2::new(p.x, p.y),
    }
}

/// The largest texel density (texels per unit) at which charts of these
/// extents, each with `gutter` texels around it, fit on shelves in a
/// `resolution`² texture, and each chart's lower corner in texels; None
/// when they do not fit at any density.
fn densest_packing(extents: &[Vec2], resolution: u32, gutter: u32) -> Option<(f32, Vec<Vec2>)> {
    let area: f32 = extents.iter().map(|e| e.x * e.y).sum();
    let longest = extents.iter().map(|e| e.max_element()).fold(0.0, f32::max);
    if extents.is_empty() || longest <= 0.0 {
        return None;
    }
    // No packing beats area = texels², nor a chart longer than the texture.
    let top =
        (resolution as f32 / area.max(f32::MIN_POSITIVE).sqrt()).min(resolution as f32 / longest);
    // Whether charts fit is not monotonic in the scale (the texel rounding
    // reorders the shelves), so walk down from the bound in 1% steps and
    // take the first that fits.
    (0..1000)
        .map(|i| top * 0.99f32.powi(i))
        .find_map(|scale| shelves(extents, resolution, gutter, scale).map(|o| (scale, o)))
}

/// Charts at `scale` texels per unit placed on shelves, tallest first;
/// None when they overflow the texture.
fn shelves(extents: &[Vec2], resolution: u32, gutter: u32, scale: f32) -> Option<Vec<Vec2>> {
    let size = |e: Vec2| (e * scale).ceil() + Vec2::splat(2.0 * gutter as f32 + 1.0);
    let mut order: Vec<usize> = (0..extents.len()).collect();
    order.sort_by(|&a, &b| size(extents[b]).y.total_cmp(&size(extents[a]).y));
    let r = resolution as f32;
    let mut origins = vec![Vec2::ZERO; extents.len()];
    let (mut x, mut y, mut shelf) = (0.0f32, 0.0f32, 0.0f32);
    for c in order {
        let s = size(extents[c]);
        if x + s.x > r {
            (x, y, shelf) = (0.0, y + shelf, 0.0);
        }
        if x + s.x > r || y + s.y > r {
            return None;
        }
        origins[c] = Vec2::new(x, y);
        x += s.x;
        shelf = shelf.max(s.y);
    }
    Some(origins)
}

#[cfg(test)]
#[path = "atlas_tests.rs"]
mod tests;
