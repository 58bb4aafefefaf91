//! Welding a triangle soup: merge vertices closer than a tolerance so adjacent patches
//! share vertices (no cracks), average their normals, but keep creases sharp.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

/// Normals of merged vertices more than ~60° apart are kept as separate vertices
/// (a crease, e.g. where the handle's end touches the body).
const CREASE_COS: f32 = 0.5;

/// The result of welding: output vertices and, per output vertex, the id of its position
/// group (vertices at a crease share a position group but not a vertex).
pub struct Welded {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub group_of_vertex: Vec<u32>,
    /// Output vertex of each input vertex.
    pub remap: Vec<u32>,
}

/// Welds vertices within `tolerance` of each other. Grid cells are `2 × tolerance` wide,
/// so every neighbour within tolerance lies in the 3×3×3 block around a vertex's cell.
pub fn weld(positions: &[Vec3], normals: &[Vec3], uvs: &[Vec2], tolerance: f32) -> Welded {
    let cell_size = 2.0 * tolerance;
    let cell = |p: Vec3| (p / cell_size).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    let mut group_pos: Vec<Vec3> = Vec::new();
    let mut group_of_input = Vec::with_capacity(positions.len());

    for &p in positions {
        let c = cell(p);
        let mut found = None;
        'search: for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let key = c + glam::IVec3::new(dx, dy, dz);
                    for &g in grid.get(&key).map(Vec::as_slice).unwrap_or(&[]) {
                        if group_pos[g as usize].distance(p) <= tolerance {
                            found = Some(g);
                            break 'search;
                        }
                    }
                }
            }
        }
        let g = found.unwrap_or_else(|| {
            let g = group_pos.len() as u32;
            group_pos.push(p);
            grid.entry(c).or_default().push(g);
            g
        });
        group_of_input.push(g);
    }

    // Within each position group, cluster by normal direction.
    let mut clusters: Vec<Vec<u32>> = vec![Vec::new(); group_pos.len()]; // output vertex ids
    let mut first_normal: Vec<Vec3> = Vec::new();
    let mut normal_sum: Vec<Vec3> = Vec::new();
    let mut out = Welded {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        group_of_vertex: Vec::new(),
        remap: Vec::with_capacity(positions.len()),
    };
    for (i, &g) in group_of_input.iter().enumerate() {
        let n = normals[i];
        let existing = clusters[g as usize]
            .iter()
            .copied()
            .find(|&v| first_normal[v as usize].dot(n) >= CREASE_COS);
        let v = existing.unwrap_or_else(|| {
            let v = out.positions.len() as u32;
            out.positions.push(group_pos[g as usize]);
            out.uvs.push(uvs[i]);
            out.group_of_vertex.push(g);
            first_normal.push(n);
            normal_sum.push(Vec3::ZERO);
            clusters[g as usize].push(v);
            v
        });
        normal_sum[v as usize] += n;
        out.remap.push(v);
    }
    out.normals = normal_sum
        .iter()
        .zip(&first_normal)
        .map(|(s, f)| s.normalize_or(*f))
        .collect();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_near_keeps_far_and_creases() {
        let p = [
            Vec3::ZERO,
            Vec3::new(1e-6, 0.0, 0.0), // merges with 0
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 1e-6), // same place as 2, but a crease
        ];
        let n = [
            Vec3::Y,
            Vec3::X.lerp(Vec3::Y, 0.9).normalize(),
            Vec3::Y,
            Vec3::X,
        ];
        let uv = [Vec2::ZERO; 4];
        let w = weld(&p, &n, &uv, 1e-5);
        assert_eq!(w.remap, vec![0, 0, 1, 2]);
        assert_eq!(w.group_of_vertex, vec![0, 1, 1]);
        assert!(w.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-6));
        assert!(w.normals[0].x > 0.0 && w.normals[0].y > 0.9);
    }
}
