//! The static refraction EM baseline (what hybrid rendering must beat): per
//! mesh vertex, the eye ray refracted once at the front surface and
//! reflected there, both looked up as directions in one cube map at
//! infinity, weighted by the same Fresnel coefficients as the greedy paths
//! (no second interface, no absorption).

use glam::Vec3;

use super::lens::Lens;
use super::path::{Path, Topology, TwoPaths};
use crate::trace::optics::{dielectric, offset, reflect, refract};

/// The baseline's two "paths" of a vertex at `p` with normal `normal` seen
/// from `eye`.
pub fn single_interface(lens: &Lens, eye: Vec3, p: Vec3, normal: Vec3) -> TwoPaths {
    let dir = (p - eye).try_normalize().unwrap_or(Vec3::NEG_Z);
    let s = Lens::vertex_surface(p, normal, dir);
    let cos_i = s.ns.dot(-dir).clamp(0.0, 1.0);
    let (f, cos_t) = dielectric(lens.ior, cos_i, s.front);
    let one = |weight: f32, dir: Vec3, origin: Vec3, exited: bool| Path {
        weight: Vec3::splat(weight),
        origin,
        dir,
        topology: Topology {
            choices: 0,
            interfaces: 1,
            exited,
        },
    };
    let r = one(
        f,
        reflect(dir, s.ns).normalize_or(s.ng),
        offset(s.p, s.ng),
        true,
    );
    let t = match cos_t {
        Some(cos_t) => one(
            1.0 - f,
            refract(dir, s.ns, lens.ior, s.front, cos_i, cos_t),
            offset(s.p, -s.ng),
            true,
        ),
        None => one(0.0, r.dir, r.origin, false),
    };
    TwoPaths { t, r }
}

/// The lens's own mesh (front-facing triangles) with every vertex's
/// baseline paths, traced in parallel: the baseline's per-frame input.
pub fn baseline_mesh(lens: &Lens, eye: Vec3) -> super::Tessellation {
    use rayon::prelude::*;
    let m = &lens.mesh;
    let normal = |i: usize| m.normals.get(i).copied().unwrap_or(Vec3::ZERO);
    let paths: Vec<TwoPaths> = (0..m.positions.len())
        .into_par_iter()
        .map(|i| single_interface(lens, eye, m.positions[i], normal(i)))
        .collect();
    let indices = m
        .indices
        .chunks_exact(3)
        .filter(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions.get(i as usize));
            matches!((a, b, c), (Some(&a), Some(&b), Some(&c)) if (b - a).cross(c - a).dot(eye - a) > 0.0)
        })
        .flatten()
        .copied()
        .collect();
    super::Tessellation {
        positions: m.positions.clone(),
        normals: (0..m.positions.len()).map(normal).collect(),
        paths,
        on: Vec::new(),
        indices,
        stats: Default::default(),
    }
}
