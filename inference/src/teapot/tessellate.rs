//! Tessellation of the teapot patches into one welded, smooth-shaded triangle mesh.

use glam::{Vec2, Vec3};

use super::TeapotPart;
use super::patch::Patch;
use super::weld::weld;
use crate::scene::error::SceneError;
use crate::scene::mesh::{Mesh, is_degenerate};

/// Upper bound on segments per patch edge (64·256² ≈ 4M triangles).
pub const MAX_SEGMENTS: u32 = 256;

/// Weld tolerance in original units (the model is ~6.4 wide). Shared patch edges agree
/// to ~1e-6; the closest distinct samples at 256 segments are ~1e-3 apart.
const WELD_TOLERANCE: f32 = 1e-5;

/// A tessellated teapot plus the welding bookkeeping the tests need.
pub struct Tessellation {
    pub mesh: Mesh,
    /// Position group of each vertex: vertices split only by a crease share a group.
    pub group_of_vertex: Vec<u32>,
}

/// Tessellates each patch of `part` into a `segments × segments` grid of quads (two
/// triangles each), welds coincident vertices, drops zero-area triangles (the collapsed
/// pole edges of lid and bottom: `8 × segments` of them for the whole teapot), and gives
/// each vertex the average of its analytic patch normals. Original units, y up, bottom
/// pole at the origin.
///
/// UVs are a cylindrical projection about the y axis (u = azimuth / 2π from −x,
/// v = height / 3.15) with a seam at −x: enough for debugging, not for texturing.
pub fn tessellate(segments: u32, part: TeapotPart) -> Result<Tessellation, SceneError> {
    if !(1..=MAX_SEGMENTS).contains(&segments) {
        return Err(SceneError::Segments {
            segments,
            max: MAX_SEGMENTS,
        });
    }
    let n = segments as usize;
    let stride = n + 1;
    let patches = part.patches();
    let mut positions = Vec::with_capacity(patches.len() * stride * stride);
    let mut normals = Vec::with_capacity(positions.capacity());
    let mut soup_indices = Vec::with_capacity(patches.len() * n * n * 6);

    for patch in patches.into_iter().filter_map(Patch::teapot) {
        let base = positions.len() as u32;
        for i in 0..=n {
            let u = i as f32 / n as f32;
            for j in 0..=n {
                let v = j as f32 / n as f32;
                positions.push(patch.eval(u, v).position);
                // `None` only for a patch collapsed in both directions (the teapot has
                // none); +y keeps the output finite if the data ever had one.
                normals.push(patch.normal(u, v).unwrap_or(Vec3::Y));
            }
        }
        for i in 0..n {
            for j in 0..n {
                let a = base + (i * stride + j) as u32;
                let (b, c, d) = (a + 1, a + stride as u32, a + stride as u32 + 1);
                // Counter-clockwise seen from outside, matching n = ∂P/∂v × ∂P/∂u.
                soup_indices.extend_from_slice(&[a, b, c, b, d, c]);
            }
        }
    }

    let uvs: Vec<Vec2> = positions.iter().map(|&p| cylindrical_uv(p)).collect();
    let welded = weld(&positions, &normals, &uvs, WELD_TOLERANCE);

    let mut indices = Vec::with_capacity(soup_indices.len());
    for tri in soup_indices.chunks_exact(3) {
        let t = [0, 1, 2].map(|k| welded.remap[tri[k] as usize]);
        let g = t.map(|v| welded.group_of_vertex[v as usize]);
        let corners = t.map(|v| welded.positions[v as usize]);
        if g[0] == g[1] || g[1] == g[2] || g[2] == g[0] || is_degenerate(corners) {
            continue;
        }
        indices.extend_from_slice(&t);
    }

    Ok(Tessellation {
        mesh: Mesh {
            positions: welded.positions,
            normals: welded.normals,
            uvs: welded.uvs,
            indices,
        },
        group_of_vertex: welded.group_of_vertex,
    })
}

fn cylindrical_uv(p: Vec3) -> Vec2 {
    let azimuth = (-p.z).atan2(-p.x); // 0 at −x, increasing counter-clockwise from above
    Vec2::new(azimuth / std::f32::consts::TAU + 0.5, p.y / super::HEIGHT)
}
