//! The hits the shells are clustered on (thesis §6.3.1): for every exit ray
//! of a view's lens vertices, every front-facing hit along it — the ray
//! continued through objects — so geometry hidden behind nearer objects
//! still votes for its layer.

use glam::Vec3;
use rayon::prelude::*;

use super::cluster::Intersection;
use super::lens::Lens;
use super::tessellate::Tessellation;
use crate::scene::Scene;
use crate::trace::SceneBvh;

/// Hits kept per ray at most.
const MAX_HITS: usize = 8;

/// Every exit ray's front-facing hits (nearest first) of `tess`'s vertices,
/// both terms; paths that never leave the lens give none.
pub fn exit_ray_hits(
    scene: &Scene,
    bvh: &SceneBvh,
    lens: &Lens,
    tess: &Tessellation,
) -> Vec<Vec<Intersection>> {
    tess.paths
        .par_iter()
        .flat_map_iter(|p| [p.t, p.r])
        .filter(|path| path.exited())
        .map(|path| continued_hits(scene, bvh, lens.object, path.origin, path.dir))
        .collect()
}

/// Front-facing hits along the ray from `origin` along `dir`, the lens
/// `skip`ped, nearest first.
pub fn continued_hits(
    scene: &Scene,
    bvh: &SceneBvh,
    skip: u32,
    origin: Vec3,
    dir: Vec3,
) -> Vec<Intersection> {
    let mut hits = Vec::new();
    let mut tmin = 0.0f32;
    for _ in 0..4 * MAX_HITS {
        let Some(h) = bvh.closest_where(origin, dir, tmin, f32::INFINITY, |o| o != skip) else {
            break;
        };
        let point = origin + dir * h.t;
        let front = scene
            .objects
            .get(h.prim.object as usize)
            .filter(|o| (h.prim.triangle as usize) < o.mesh.triangle_count())
            .is_some_and(|o| {
                let [a, b, c] = o.mesh.triangle(h.prim.triangle as usize);
                (b - a).cross(c - a).dot(dir) < 0.0
            });
        if front {
            hits.push(Intersection {
                object: h.prim.object,
                point,
            });
            if hits.len() == MAX_HITS {
                break;
            }
        }
        // Past this hit, scaled to the distance so f32 rounding cannot stall.
        tmin = h.t + 1e-4 * h.t.max(1.0);
    }
    hits
}
