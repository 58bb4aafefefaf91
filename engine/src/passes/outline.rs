//! Where a reflector's outline can lie on screen, as rows of lavapipe's
//! 4×4 tiles, for the edge filter ([`super::edge_filter`]): the filter
//! then runs over a few thousand pixels instead of every pixel the
//! reflector covers (lavapipe shades whole 4×4 tiles, whatever a
//! fragment shader then discards).
//!
//! What the rasterizer covers of a mesh drawn with back faces culled is
//! bounded by its contour edges: those between a triangle facing the eye
//! and one facing away, and the mesh's open edges (where its inside caps
//! begin). A pixel whose coverage differs from a neighbour's has such an
//! edge within one pixel, so the tiles within 1.5 pixels of every contour
//! edge hold the whole outline. Per frame that is one sign per triangle
//! and a few tiles per contour edge, from the vertices' screen positions
//! the compositing bands already computed.

use super::bands::BAND_ROWS;
use ash::vk;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Tile size in pixels (both ways).
const TILE: u32 = BAND_ROWS;
/// How far from a contour edge a pixel on the outline, or one of its
/// neighbours, can lie: one pixel, and half a pixel from centre to edge.
const REACH: f32 = 1.5;
/// Long edges are walked in pieces of at most this many pixels, so one
/// edge across the screen marks the tiles along it, not its bounding box.
const PIECE: f32 = TILE as f32;

/// A mesh's edges with the triangles on either side, its vertices welded
/// by position (a mesh split at seams for its normals or UVs is still
/// closed there).
pub struct MeshEdges {
    /// The triangles on either side of each edge; an open edge's second
    /// is `triangles` (one past the last), whose facing reads 0.
    sides: Vec<[u32; 2]>,
    /// The vertex indices of each edge's ends.
    ends: Vec<[u32; 2]>,
    triangles: usize,
}

impl MeshEdges {
    pub fn new(positions: &[Vec3], triangles: &[u32]) -> Self {
        let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
        let weld: Vec<u32> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                *welded
                    .entry(p.to_array().map(f32::to_bits))
                    .or_insert(i as u32)
            })
            .collect();
        let key = |v: u32| weld.get(v as usize).copied().unwrap_or(v);
        let count = triangles.len() / 3;
        let open = count as u32;
        let mut by_ends: HashMap<(u32, u32), usize> = HashMap::new();
        let (mut sides, mut ends): (Vec<[u32; 2]>, Vec<[u32; 2]>) = (Vec::new(), Vec::new());
        for (t, tri) in triangles.chunks_exact(3).enumerate() {
            for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
                let (ka, kb) = (key(a), key(b));
                match by_ends.get(&(ka.min(kb), ka.max(kb))) {
                    // A second triangle on this edge (a third one, on a
                    // non-manifold edge, is left out: the first two bound it).
                    Some(&e) if sides[e][1] == open => sides[e][1] = t as u32,
                    Some(_) => {}
                    None => {
                        by_ends.insert((ka.min(kb), ka.max(kb)), sides.len());
                        sides.push([t as u32, open]);
                        ends.push([a, b]);
                    }
                }
            }
        }
        Self {
            sides,
            ends,
            triangles: count,
        }
    }

    /// Tile-aligned rectangles (one per run of marked tiles in a tile row)
    /// holding every pixel of a `width × height` frame within one pixel of
    /// where the coverage of `triangles` changes, given each vertex's
    /// screen position (`pixels`, from [`super::bands::screen_bands`]).
    /// None when an index is out of range or `triangles` is not the mesh's.
    pub fn outline_tiles(
        &self,
        pixels: &[Vec2],
        triangles: &[u32],
        (width, height): (u32, u32),
    ) -> Option<Vec<vk::Rect2D>> {
        if triangles.len() / 3 != self.triangles {
            return None;
        }
        if width == 0 || height == 0 {
            return Some(Vec::new());
        }
        // Which way each triangle faces on screen; zero area (or NaN)
        // counts as neither, so its edges are marked. One more entry, 0,
        // for the open edges' missing side.
        let mut facing = Vec::with_capacity(self.triangles + 1);
        for t in triangles.chunks_exact(3) {
            let a = *pixels.get(t[0] as usize)?;
            let b = *pixels.get(t[1] as usize)?;
            let c = *pixels.get(t[2] as usize)?;
            let area = (b - a).perp_dot(c - a);
            facing.push((area > 0.0) as i8 - (area < 0.0) as i8);
        }
        facing.push(0);
        let mut tiles = Tiles::new(width, height);
        for (side, end) in self.sides.iter().zip(&self.ends) {
            let (s0, s1) = (facing[side[0] as usize], facing[side[1] as usize]);
            if s0 != s1 || s0 == 0 {
                let (a, b) = (*pixels.get(end[0] as usize)?, *pixels.get(end[1] as usize)?);
                tiles.mark_segment(a, b);
            }
        }
        Some(tiles.runs())
    }
}

/// Which tiles of a frame are marked.
struct Tiles {
    columns: u32,
    rows: u32,
    size: (u32, u32),
    marked: Vec<bool>,
}

impl Tiles {
    fn new(width: u32, height: u32) -> Self {
        let (columns, rows) = (width.div_ceil(TILE), height.div_ceil(TILE));
        Self {
            columns,
            rows,
            size: (width, height),
            marked: vec![false; (columns * rows) as usize],
        }
    }

    /// Marks the tiles within `REACH` of the segment `a`–`b`.
    fn mark_segment(&mut self, a: Vec2, b: Vec2) {
        if !(a.is_finite() && b.is_finite()) {
            return;
        }
        let pieces = ((b - a).length() / PIECE).ceil().clamp(1.0, 4096.0) as u32;
        for i in 0..pieces {
            let p = a.lerp(b, i as f32 / pieces as f32);
            let q = a.lerp(b, (i + 1) as f32 / pieces as f32);
            self.mark_box(p.min(q) - REACH, p.max(q) + REACH);
        }
    }

    fn mark_box(&mut self, lo: Vec2, hi: Vec2) {
        let tile = |v: f32, count: u32| (v.max(0.0) as u32 / TILE).min(count - 1);
        if hi.x < 0.0 || hi.y < 0.0 || lo.x >= self.size.0 as f32 || lo.y >= self.size.1 as f32 {
            return;
        }
        let (x0, x1) = (tile(lo.x, self.columns), tile(hi.x, self.columns));
        let (y0, y1) = (tile(lo.y, self.rows), tile(hi.y, self.rows));
        for y in y0..=y1 {
            let row = (y * self.columns) as usize;
            self.marked[row + x0 as usize..=row + x1 as usize].fill(true);
        }
    }

    /// One rectangle per run of marked tiles in a row, clipped to the frame.
    fn runs(&self) -> Vec<vk::Rect2D> {
        let mut out = Vec::new();
        for y in 0..self.rows {
            let row = &self.marked[(y * self.columns) as usize..][..self.columns as usize];
            let mut x = 0;
            while x < self.columns {
                if !row[x as usize] {
                    x += 1;
                    continue;
                }
                let start = x;
                while x < self.columns && row[x as usize] {
                    x += 1;
                }
                let (px, py) = (start * TILE, y * TILE);
                out.push(vk::Rect2D {
                    offset: vk::Offset2D {
                        x: px as i32,
                        y: py as i32,
                    },
                    extent: vk::Extent2D {
                        width: (x * TILE).min(self.size.0) - px,
                        height: TILE.min(self.size.1 - py),
                    },
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::bands::screen_bands;

    /// Rasterizes front-facing (counter-clockwise on screen, y down)
    /// triangles at pixel centres, as the G-buffer pass covers them.
    fn coverage(pixels: &[Vec2], triangles: &[u32], (w, h): (u32, u32)) -> Vec<bool> {
        let mut out = vec![false; (w * h) as usize];
        for t in triangles.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| pixels[i as usize]);
            if (b - a).perp_dot(c - a) <= 0.0 {
                continue;
            }
            for y in 0..h {
                for x in 0..w {
                    let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let inside = [(a, b), (b, c), (c, a)]
                        .iter()
                        .all(|&(u, v)| (v - u).perp_dot(p - u) >= 0.0);
                    out[(y * w + x) as usize] |= inside;
                }
            }
        }
        out
    }

    /// A UV sphere split at its seam (duplicated vertices), as meshes are.
    fn sphere(rings: u32, segments: u32) -> (Vec<Vec3>, Vec<u32>) {
        let mut positions = Vec::new();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = std::f32::consts::TAU * (s % segments) as f32 / segments as f32;
                let (st, ct) = theta.sin_cos();
                let (sp, cp) = phi.sin_cos();
                positions.push(Vec3::new(st * cp, ct, st * sp));
            }
        }
        let mut triangles = Vec::new();
        let at = |r: u32, s: u32| r * (segments + 1) + s;
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
                triangles.extend([a, b, c, b, d, c]);
            }
        }
        (positions, triangles)
    }

    fn inside(x: u32, y: u32, r: &vk::Rect2D) -> bool {
        let (x, y) = (x as i32, y as i32);
        x >= r.offset.x
            && y >= r.offset.y
            && x < r.offset.x + r.extent.width as i32
            && y < r.offset.y + r.extent.height as i32
    }

    #[test]
    fn the_tiles_hold_every_pixel_next_to_a_coverage_step() {
        let (positions, triangles) = sphere(12, 20);
        let edges = MeshEdges::new(&positions, &triangles);
        let size = (96, 72);
        for (eye, target) in [
            (Vec3::new(0.0, 0.5, 3.0), Vec3::ZERO),
            (Vec3::new(2.0, 1.5, 1.0), Vec3::new(0.3, 0.0, 0.0)),
        ] {
            let view = glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y);
            let proj = glam::camera::rh::proj::vulkan::perspective(0.9, 96.0 / 72.0, 0.1, 10.0);
            let view_proj = proj * view;
            let mut pixels = Vec::new();
            screen_bands(view_proj, &positions, &triangles, size, &mut pixels).unwrap();
            let tiles = edges.outline_tiles(&pixels, &triangles, size).unwrap();
            let covered = coverage(&pixels, &triangles, size);
            assert!(covered.iter().any(|&c| c), "the sphere is in view");
            let at = |x: i32, y: i32| {
                let (x, y) = (x.clamp(0, 95) as u32, y.clamp(0, 71) as u32);
                covered[(y * 96 + x) as usize]
            };
            let mut outline = 0;
            for y in 0..72 {
                for x in 0..96 {
                    let c = at(x, y);
                    let step = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                        .iter()
                        .any(|&(dx, dy)| at(x + dx, y + dy) != c);
                    if step {
                        outline += 1;
                        let (x, y) = (x as u32, y as u32);
                        assert!(tiles.iter().any(|r| inside(x, y, r)), "({x}, {y})");
                    }
                }
            }
            // Far fewer pixels than the sphere covers (its inside is left out).
            let tiled: u32 = tiles.iter().map(|r| r.extent.width * r.extent.height).sum();
            let area = covered.iter().filter(|&&c| c).count() as u32;
            assert!(outline > 0 && tiled < area, "{tiled} tiled, {area} covered");
        }
    }

    #[test]
    fn an_open_mesh_marks_its_rim_and_a_bad_index_is_refused() {
        // One quad facing the eye: every edge is open.
        let positions = [(0.0, 0.0), (40.0, 0.0), (40.0, 40.0), (0.0, 40.0)]
            .map(|(x, y)| Vec3::new(x, y, 0.0))
            .to_vec();
        let triangles = vec![0, 1, 2, 0, 2, 3];
        let edges = MeshEdges::new(&positions, &triangles);
        let pixels: Vec<Vec2> = positions.iter().map(|p| p.truncate() + 10.0).collect();
        let tiles = edges.outline_tiles(&pixels, &triangles, (64, 64)).unwrap();
        // The rim's tiles, not the quad's inside.
        assert!(tiles.iter().any(|r| inside(10, 30, r)));
        assert!(!tiles.iter().any(|r| inside(30, 30, r)));
        assert!(
            edges
                .outline_tiles(&pixels[..3], &triangles, (64, 64))
                .is_none()
        );
        // An empty frame has no tiles (and no tile to clamp to).
        let empty = edges.outline_tiles(&pixels, &triangles, (0, 64));
        assert!(empty.is_some_and(|t| t.is_empty()));
    }
}
