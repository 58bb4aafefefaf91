//! Adaptive tessellation of the lens for one view (thesis §6.4.1): rays are
//! traced at the front-facing triangles' vertices; a triangle whose
//! vertices' paths differ — in topology, or in exit direction by more than
//! 3° — has its edges longer than τ subpixels split at their midpoints
//! (1→4, 1→3 or 1→2), level by level, each level's new vertices traced in
//! parallel. An edge hash keeps each midpoint once; the leaves are then
//! re-triangulated against every midpoint on their edges, so the mesh has
//! no T-junctions.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::{Mat4, Vec2, Vec3};
use rayon::prelude::*;

use super::lens::Lens;
use super::path::{AngleLimit, TwoPaths, vertex_paths};

/// A working triangle: its corners and the lens triangle it lies in.
type Piece = ([u32; 3], u32);

/// Subpixels per pixel along x and y: the thesis measured τ on a 3×3
/// supersampled frame.
pub const SUBPIXELS: f32 = 3.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TessSettings {
    /// Split edges longer than this, in subpixels.
    pub tau: f32,
    /// Exit directions further apart than this differ (thesis: 3°).
    pub max_angle_deg: f32,
    /// Subdivision levels at most (bounds the work for tiny τ).
    pub max_depth: u32,
    /// Vertices at most; past it, remaining triangles stay as they are.
    pub max_vertices: usize,
}

impl TessSettings {
    pub fn new(tau: f32) -> Self {
        Self {
            tau,
            max_angle_deg: 3.0,
            max_depth: 8,
            max_vertices: 1 << 20,
        }
    }
}

/// Where world points land on the frame, in pixels.
#[derive(Clone, Copy, Debug)]
pub struct Screen {
    pub view_proj: Mat4,
    pub width: u32,
    pub height: u32,
}

impl Screen {
    /// Pixel position of `p`; None behind (or at) the eye, where no length
    /// can be measured.
    pub fn pixel(&self, p: Vec3) -> Option<Vec2> {
        let c = self.view_proj * p.extend(1.0);
        if c.w.is_nan() || c.w <= 1e-6 {
            return None;
        }
        let ndc = Vec2::new(c.x, c.y) / c.w;
        let px = (ndc * 0.5 + 0.5) * Vec2::new(self.width as f32, self.height as f32);
        px.is_finite().then_some(px)
    }
}

/// The tessellated lens of one view: vertices with their paths, and
/// front-facing triangles only (back faces would be culled anyway).
#[derive(Clone, Debug, Default)]
pub struct Tessellation {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub paths: Vec<TwoPaths>,
    /// Per vertex, a lens triangle whose plane holds it (a hull triangle
    /// where one does): rays leaving it outwards may skip their traversal.
    /// Empty for the static baseline's mesh, which casts no rays.
    pub on: Vec<u32>,
    pub indices: Vec<u32>,
    pub stats: TessStats,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TessStats {
    /// Vertices of the base mesh that were traced (front-facing triangles).
    pub base_vertices: usize,
    /// Midpoints added.
    pub added_vertices: usize,
    /// Rays cast through the lens (one per interface met or exit).
    pub rays: u64,
    /// Subdivision levels used.
    pub depth: u32,
    /// The vertex budget stopped subdivision early.
    pub budget_hit: bool,
}

/// A fast hasher for the edge keys (two vertex indices in one u64).
#[derive(Default)]
struct EdgeHasher(u64);

impl Hasher for EdgeHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (x ^ (x >> 29)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    }
}

type EdgeMap = HashMap<u64, u32, BuildHasherDefault<EdgeHasher>>;

fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// The working mesh: vertices, their paths and pixels, and the edge hash.
struct Work<'a> {
    lens: &'a Lens,
    eye: Vec3,
    screen: Screen,
    settings: TessSettings,
    angle_limit: AngleLimit,
    out: Tessellation,
    pixels: Vec<Option<Vec2>>,
    midpoints: EdgeMap,
}

/// Tessellates `lens` for the eye at `eye` seen through `screen`.
pub fn tessellate(lens: &Lens, eye: Vec3, screen: Screen, settings: TessSettings) -> Tessellation {
    let mesh = &lens.mesh;
    let mut map = vec![u32::MAX; mesh.positions.len()];
    let mut work = Work {
        lens,
        eye,
        screen,
        settings,
        angle_limit: AngleLimit::new(settings.max_angle_deg),
        out: Tessellation::default(),
        pixels: Vec::new(),
        midpoints: EdgeMap::default(),
    };
    let mut active: Vec<Piece> = Vec::new();
    let mut fresh: Vec<(Vec3, Vec3)> = Vec::new();
    let mut on: Vec<u32> = Vec::new();
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let t = t as u32;
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let (Some(&pa), Some(&pb), Some(&pc)) = (
            mesh.positions.get(a),
            mesh.positions.get(b),
            mesh.positions.get(c),
        ) else {
            continue;
        };
        // Outward winding: front-facing when the eye is on the normal's side.
        if (pb - pa).cross(pc - pa).dot(eye - pa) <= 0.0 {
            continue;
        }
        let mut corner = |i: usize| {
            if map[i] == u32::MAX {
                map[i] = fresh.len() as u32;
                let n = mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
                fresh.push((mesh.positions[i], n));
                on.push(t);
            }
            let v = map[i] as usize;
            if lens.on_hull(t) && !lens.on_hull(on[v]) {
                on[v] = t;
            }
            map[i]
        };
        active.push(([a, b, c].map(&mut corner), t));
    }
    work.add_vertices(&fresh, &on);
    work.out.stats.base_vertices = fresh.len();
    let leaves = work.refine(active);
    let emitted: Vec<Vec<u32>> = leaves
        .par_chunks(1024)
        .map(|chunk| {
            let mut indices = Vec::with_capacity(chunk.len() * 3);
            for &([a, b, c], _) in chunk {
                work.emit([a, b, c], 0, &mut indices);
            }
            indices
        })
        .collect();
    work.out.indices = emitted.concat();
    work.out
}

impl Work<'_> {
    /// Appends vertices (position, normal) lying on lens triangles `on`,
    /// traces their paths in parallel.
    fn add_vertices(&mut self, vertices: &[(Vec3, Vec3)], on: &[u32]) {
        debug_assert_eq!(vertices.len(), on.len());
        let (lens, eye, screen) = (self.lens, self.eye, self.screen);
        let traced: Vec<TwoPaths> = vertices
            .par_iter()
            .zip(on)
            .map(|(&v, &t)| vertex_paths(lens, eye, v, Some(t)))
            .collect();
        self.out.on.extend_from_slice(on);
        for (&(p, n), paths) in vertices.iter().zip(traced) {
            self.out.stats.rays +=
                u64::from(paths.t.topology.interfaces) + u64::from(paths.r.topology.interfaces);
            self.out.positions.push(p);
            self.out.normals.push(n);
            self.out.paths.push(paths);
            self.pixels.push(screen.pixel(p));
        }
    }

    /// Subdivides level by level; returns the leaf triangles.
    fn refine(&mut self, mut active: Vec<Piece>) -> Vec<Piece> {
        let mut leaves = Vec::with_capacity(active.len());
        for depth in 0..self.settings.max_depth {
            let mut splitting: Vec<(Piece, u8)> = Vec::new();
            let mut queued: Vec<(u32, u32)> = Vec::new();
            let mut on: Vec<u32> = Vec::new();
            let mut seen = EdgeMap::default();
            // The masks only read the mesh: in parallel, in order.
            let masks: Vec<u8> = active
                .par_iter()
                .map(|&(t, _)| self.split_mask(t))
                .collect();
            for ((tri, home), mask) in active.drain(..).zip(masks) {
                if mask == 0 {
                    leaves.push((tri, home));
                    continue;
                }
                for e in 0..3 {
                    let (a, b) = (tri[e], tri[(e + 1) % 3]);
                    let key = edge_key(a, b);
                    if mask & (1 << e) != 0
                        && !self.midpoints.contains_key(&key)
                        && seen.insert(key, 0).is_none()
                    {
                        queued.push((a, b));
                        on.push(home);
                    }
                }
                splitting.push(((tri, home), mask));
            }
            if splitting.is_empty() {
                break;
            }
            if self.out.positions.len() + queued.len() > self.settings.max_vertices {
                self.out.stats.budget_hit = true;
                leaves.extend(splitting.into_iter().map(|(t, _)| t));
                break;
            }
            self.out.stats.depth = depth + 1;
            let first = self.out.positions.len() as u32;
            let fresh: Vec<(Vec3, Vec3)> = queued
                .iter()
                .map(|&(a, b)| {
                    let (pa, pb) = (
                        self.out.positions[a as usize],
                        self.out.positions[b as usize],
                    );
                    let (na, nb) = (self.out.normals[a as usize], self.out.normals[b as usize]);
                    ((pa + pb) * 0.5, (na + nb).normalize_or(na))
                })
                .collect();
            for (i, &(a, b)) in queued.iter().enumerate() {
                self.midpoints.insert(edge_key(a, b), first + i as u32);
            }
            self.out.stats.added_vertices += fresh.len();
            self.add_vertices(&fresh, &on);
            let children: Vec<Vec<Piece>> = splitting
                .par_iter()
                .map(|&((tri, home), mask)| {
                    let pieces = self.children(tri, mask).into_iter();
                    pieces.map(|child| (child, home)).collect()
                })
                .collect();
            active.extend(children.into_iter().flatten());
        }
        leaves.extend(active);
        leaves
    }

    /// Edges (bit e = edge from corner e to e+1) to split: the long ones,
    /// when the corners' paths differ.
    fn split_mask(&self, tri: [u32; 3]) -> u8 {
        let paths = tri.map(|i| &self.out.paths[i as usize]);
        let differ = (0..3).any(|e| self.differ(paths[e], paths[(e + 1) % 3]));
        if !differ {
            return 0;
        }
        let limit = self.settings.tau / SUBPIXELS;
        let mut mask = 0;
        for e in 0..3 {
            let (a, b) = (tri[e] as usize, tri[(e + 1) % 3] as usize);
            // Behind the eye no length can be measured: leave it.
            if let (Some(pa), Some(pb)) = (self.pixels[a], self.pixels[b])
                && pa.distance(pb) > limit
            {
                mask |= 1 << e;
            }
        }
        mask
    }

    fn differ(&self, a: &TwoPaths, b: &TwoPaths) -> bool {
        let limit = self.angle_limit;
        [(&a.t, &b.t), (&a.r, &b.r)]
            .iter()
            .any(|(p, q)| p.topology != q.topology || (p.exited() && limit.exceeded(p.dir, q.dir)))
    }

    /// The triangles `tri` becomes when the edges of `mask` are split (their
    /// midpoints are in the hash), winding kept.
    fn children(&self, tri: [u32; 3], mask: u8) -> Vec<[u32; 3]> {
        let mid = |e: usize| {
            self.midpoints
                .get(&edge_key(tri[e], tri[(e + 1) % 3]))
                .copied()
        };
        let m = [0, 1, 2].map(|e| if mask & (1 << e) != 0 { mid(e) } else { None });
        split_pattern(tri, m)
    }

    /// Appends `tri` re-triangulated against every midpoint on its
    /// edges (recursively), so neighbours that were split further meet it
    /// without T-junctions.
    fn emit(&self, tri: [u32; 3], depth: u32, indices: &mut Vec<u32>) {
        let m = [0, 1, 2].map(|e| {
            self.midpoints
                .get(&edge_key(tri[e], tri[(e + 1) % 3]))
                .copied()
        });
        // Every split adds a level; the hash cannot hold deeper ones.
        if m.iter().all(Option::is_none) || depth > 2 * self.settings.max_depth + 2 {
            indices.extend_from_slice(&tri);
            return;
        }
        for child in split_pattern(tri, m) {
            self.emit(child, depth + 1, indices);
        }
    }
}

/// The children of `tri` with midpoints `m[e]` on the split edges
/// (edge e runs from corner e to corner e+1): 1→2, 1→3 or 1→4.
fn split_pattern(tri: [u32; 3], m: [Option<u32>; 3]) -> Vec<[u32; 3]> {
    let splits = m.iter().filter(|x| x.is_some()).count();
    // Rotate so the pattern starts at edge 0 (corners a, b, c).
    let r = match splits {
        1 => m.iter().position(Option::is_some).unwrap_or(0),
        2 => m
            .iter()
            .position(Option::is_none)
            .map_or(0, |e| (e + 1) % 3),
        _ => 0,
    };
    let [a, b, c] = [tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]];
    let [mab, mbc, mca] = [m[r], m[(r + 1) % 3], m[(r + 2) % 3]];
    match (mab, mbc, mca) {
        (Some(x), Some(y), Some(z)) => vec![[a, x, z], [x, b, y], [z, y, c], [x, y, z]],
        (Some(x), Some(y), None) => vec![[x, b, y], [a, x, y], [a, y, c]],
        (Some(x), None, None) => vec![[a, x, c], [x, b, c]],
        _ => vec![[a, b, c]],
    }
}
