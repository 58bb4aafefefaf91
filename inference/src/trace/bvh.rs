//! The scene's triangles in one obvhs compressed wide BVH (CWBVH), with closest-hit and
//! shadow queries. Triangles are stored in BVH order so traversal indexes them directly.

use std::time::{Duration, Instant};

use glam::{Vec2, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;

use crate::scene::{Mesh, Scene};

/// Which object and which of its triangles a BVH primitive is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimRef {
    pub object: u32,
    pub triangle: u32,
}

/// A closest hit: distance, what was hit and the barycentrics `(b1, b2)` of the hit point
/// (`p = (1 − b1 − b2)·v0 + b1·v1 + b2·v2` in the mesh's vertex order).
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub prim: PrimRef,
    pub bary: Vec2,
}

pub struct SceneBvh {
    /// `None` for a scene without triangles: every ray misses.
    bvh: Option<CwBvh>,
    tris: Vec<Triangle>,
    prims: Vec<PrimRef>,
    /// Wall-clock BVH build time (triangle gathering included).
    pub build_time: Duration,
}

impl SceneBvh {
    pub fn build(scene: &Scene) -> SceneBvh {
        let meshes: Vec<(u32, &Mesh)> = scene
            .objects
            .iter()
            .enumerate()
            .map(|(o, object)| (o as u32, object.traced_mesh()))
            .collect();
        SceneBvh::from_meshes(&meshes)
    }

    /// A BVH over some meshes only, each tagged with the object index its
    /// hits report (the glass lens: one object in its own BVH).
    pub fn from_meshes(meshes: &[(u32, &Mesh)]) -> SceneBvh {
        let start = Instant::now();
        let mut tris = Vec::new();
        let mut prims = Vec::new();
        for &(o, mesh) in meshes {
            for t in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(t);
                tris.push(Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                });
                prims.push(PrimRef {
                    object: o,
                    triangle: t as u32,
                });
            }
        }
        if tris.is_empty() {
            return SceneBvh {
                bvh: None,
                tris,
                prims,
                build_time: start.elapsed(),
            };
        }
        let bvh = build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::slow_build(),
            &mut Duration::default(),
        );
        // Lay primitives out in BVH order (spatial splits may reference one twice).
        let (tris, prims) = bvh
            .primitive_indices
            .iter()
            .map(|&i| (tris[i as usize], prims[i as usize]))
            .unzip();
        SceneBvh {
            bvh: Some(bvh),
            tris,
            prims,
            build_time: start.elapsed(),
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Nearest hit with `t` in `[tmin, tmax]`; triangles of object `skip` are transparent.
    pub fn closest(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        skip: Option<u32>,
    ) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = make_ray(origin, dir, tmin, tmax);
        let mut hit = RayHit::none();
        let found = match skip {
            None => bvh.ray_traverse(ray, &mut hit, |r, id| self.tris[id].intersect(r)),
            Some(s) => bvh.ray_traverse(ray, &mut hit, |r, id| {
                if self.prims[id].object == s {
                    f32::INFINITY
                } else {
                    self.tris[id].intersect(r)
                }
            }),
        };
        if !found {
            return None;
        }
        let id = hit.primitive_id as usize;
        let tri = self.tris.get(id)?;
        Some(Hit {
            t: hit.t,
            prim: self.prims[id],
            bary: barycentrics(tri, origin + dir * hit.t),
        })
    }

    /// Nearest hit with `t` in `[tmin, tmax]` on an object `keep` accepts;
    /// every other object is transparent (the glass targets' continued rays).
    pub fn closest_where(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        keep: impl Fn(u32) -> bool,
    ) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = make_ray(origin, dir, tmin, tmax);
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(ray, &mut hit, |r, id| {
            if keep(self.prims[id].object) {
                self.tris[id].intersect(r)
            } else {
                f32::INFINITY
            }
        });
        if !found {
            return None;
        }
        let id = hit.primitive_id as usize;
        let tri = self.tris.get(id)?;
        Some(Hit {
            t: hit.t,
            prim: self.prims[id],
            bary: barycentrics(tri, origin + dir * hit.t),
        })
    }

    /// True when anything lies on the segment `origin + t·dir`, `t` in `[tmin, tmax]`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let ray = make_ray(origin, dir, tmin, tmax);
        !bvh.ray_traverse_miss(ray, |r, id| self.tris[id].intersect(r))
    }
}

impl SceneBvh {
    /// As [`SceneBvh::occluded`], counting only objects `blocks` accepts (directional
    /// light, which the room's box lets through).
    pub fn occluded_where(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        blocks: impl Fn(u32) -> bool,
    ) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let ray = make_ray(origin, dir, tmin, tmax);
        !bvh.ray_traverse_miss(ray, |r, id| {
            if blocks(self.prims[id].object) {
                self.tris[id].intersect(r)
            } else {
                f32::INFINITY
            }
        })
    }
}

/// obvhs 0.4's traversal misses every node for a direction with a −0.0 component (e.g.
/// `-Vec3::Y`): its octant test and its inverse direction disagree. Adding +0.0 turns −0.0
/// into +0.0 and leaves every other value unchanged.
fn make_ray(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Ray {
    let dir = dir + Vec3::ZERO;
    Ray::new(Vec3A::from(origin), Vec3A::from(dir), tmin, tmax)
}

/// Barycentrics of point `p` (on or near the triangle's plane), clamped into the triangle
/// so attribute interpolation never extrapolates; a degenerate triangle gives its corner v0.
fn barycentrics(tri: &Triangle, p: Vec3) -> Vec2 {
    let (a, b, c) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dp1, dp2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if den.abs().partial_cmp(&f32::MIN_POSITIVE) != Some(std::cmp::Ordering::Greater) {
        return Vec2::ZERO;
    }
    let b1 = (d22 * dp1 - d12 * dp2) / den;
    let b2 = (d11 * dp2 - d12 * dp1) / den;
    let bary = Vec2::new(b1, b2).clamp(Vec2::ZERO, Vec2::ONE);
    if !bary.is_finite() {
        return Vec2::ZERO;
    }
    let s = bary.x + bary.y;
    if s > 1.0 { bary / s } else { bary }
}
