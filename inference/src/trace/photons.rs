//! The caustic photon map: light that reaches a diffuse surface only through mirrors,
//! glossy or glass objects (light → specular⁺ → diffuse), which light sampling at the
//! diffuse hit cannot find.
//!
//! Photons leave each area light toward each reflective object's bounding sphere (a cone
//! per point on the light), follow the camera paths' own specular rules
//! ([`Integrator::specular_bounce`]) and are stored at the first diffuse surface they hit.
//! A photon whose first hit is not the object it was aimed at carries direct light (or
//! another object's caustic, sampled by that object's cone) and is dropped. So every
//! light → specular⁺ → diffuse path is counted once here, and since camera paths skip
//! emitters found by a bounce, nothing is counted twice.
//!
//! A diffuse hit reads the kernel estimate of the photons' irradiance, pre-filtered onto a
//! lattice ([`super::lattice`]): a fine one (radius r) at a path's first diffuse hit, a
//! coarse one (4r) after a diffuse bounce. The estimate adds no per-sample noise; it
//! blurs the caustic by the kernel radius `r` and carries the photon count's own
//! (low-frequency) noise.
//!
//! Deterministic: photon `i` aimed at pair `j` (light, object) draws from its own stream
//! and photons are splatted in batch order, so the map and every lookup are bit-identical
//! at any thread count. The map does not depend on the view: every view of a scene with
//! the same seed sees the same caustic.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::lattice::Lattice;
use super::optics::offset;
use super::rng::{Rng, basis};
use super::shading::Integrator;
use crate::scene::{AreaLight, Material};

/// Photons traced per parallel batch (fixed, so batches do not depend on thread count).
const BATCH: u32 = 4096;
/// Random stream of photon paths (camera samples use 0 and 1).
const STREAM: u32 = 2;
/// Kernel radius of the coarse lattice, in fine radii.
const COARSE: f32 = 4.0;

#[derive(Clone, Copy, Debug)]
struct Photon {
    p: Vec3,
    /// Geometric normal on the side the photon arrived from.
    n: Vec3,
    /// Flux, W per channel.
    power: Vec3,
}

/// Photons aimed from one light at one reflective object.
#[derive(Clone, Copy, Debug)]
struct Target {
    light: usize,
    object: u32,
    center: Vec3,
    radius: f32,
    count: u32,
}

/// The caustic photons, pre-filtered onto a lattice ([`super::lattice`]).
pub struct PhotonMap {
    lattice: Lattice,
    coarse: Lattice,
    /// Photon paths traced (aimed at reflective objects).
    pub emitted: u64,
    /// Photons stored (paths that reached a diffuse surface through a reflector).
    pub stored: u64,
    /// Rays traced to build the map.
    pub rays: u64,
}

impl PhotonMap {
    /// Traces about `photons` paths (split over light/object pairs by the flux they aim)
    /// and filters the stored photons with a kernel of `radius` metres.
    pub fn build(integrator: &Integrator, photons: u32, radius: f32, seed: u64) -> PhotonMap {
        let targets = targets(integrator, photons);
        let batches: Vec<(usize, u32, u32)> = targets
            .iter()
            .enumerate()
            .flat_map(|(j, t)| {
                (0..t.count.div_ceil(BATCH))
                    .map(move |b| (j, b * BATCH, (b * BATCH + BATCH).min(t.count)))
            })
            .collect();
        let traced: Vec<(Vec<Photon>, u64)> = batches
            .par_iter()
            .map(|&(j, start, end)| {
                let (mut out, mut rays) = (Vec::new(), 0u64);
                for i in start..end {
                    let mut rng = Rng::new(seed, u64::MAX - j as u64, i, STREAM);
                    trace_photon(integrator, &targets[j], &mut rng, &mut out, &mut rays);
                }
                (out, rays)
            })
            .collect();
        // In batch order: the sums are the same whatever the thread count.
        let mut lattice = Lattice::new(radius);
        let mut coarse = Lattice::new(radius * COARSE);
        let mut stored = 0;
        for ph in traced.iter().flat_map(|(p, _)| p) {
            lattice.splat(ph.p, ph.n, ph.power);
            coarse.splat(ph.p, ph.n, ph.power);
            stored += 1;
        }
        lattice.finish();
        coarse.finish();
        PhotonMap {
            lattice,
            coarse,
            emitted: targets.iter().map(|t| u64::from(t.count)).sum(),
            stored,
            rays: traced.iter().map(|(_, r)| r).sum(),
        }
    }

    /// Bytes of the fine and the coarse lattice.
    pub fn bytes(&self) -> (usize, usize) {
        (self.lattice.bytes(), self.coarse.bytes())
    }

    /// Caustic irradiance at `p` on a surface with normal `n` (facing the viewer), W/m².
    pub fn irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        self.lattice.irradiance(p, n)
    }

    /// The same blurred over `COARSE` times the radius, from a lattice small enough to stay
    /// in cache: for hits reached by a diffuse bounce, which are scattered over the scene.
    pub fn coarse_irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        self.coarse.irradiance(p, n)
    }
}

/// Light/object pairs with their share of the photons, by the flux each cone carries.
fn targets(integrator: &Integrator, photons: u32) -> Vec<Target> {
    let scene = integrator.scene;
    let mut out = Vec::new();
    for light in 0..scene.lights.len() {
        for (object, o) in scene.objects.iter().enumerate() {
            let reflective = matches!(
                scene.materials.get(o.material),
                Some(Material::Mirror { .. } | Material::Glossy { .. } | Material::Glass { .. })
            );
            let mesh = o.traced_mesh();
            if !reflective || mesh.positions.is_empty() {
                continue;
            }
            let (lo, hi) = mesh.bounds();
            let center = 0.5 * (lo + hi);
            let radius = mesh
                .positions
                .iter()
                .map(|p| p.distance(center))
                .fold(0.0f32, f32::max);
            out.push(Target {
                light,
                object: object as u32,
                center,
                radius,
                count: 0,
            });
        }
    }
    let weight = |t: &Target| {
        let l = &scene.lights[t.light];
        let flux = l.radiance.dot(Vec3::splat(1.0 / 3.0)) * l.area();
        let w = flux * cone(t.center - l.center, t.radius).1;
        if w.is_finite() { w.max(0.0) } else { 0.0 }
    };
    let total: f32 = out.iter().map(weight).sum();
    if total > 0.0 {
        for t in &mut out {
            t.count = (f64::from(photons) * f64::from(weight(t) / total)).round() as u32;
        }
    }
    out.retain(|t| t.count > 0);
    out
}

/// Axis and `1 − cos θmax` of the cone from a point `to` away from a sphere's centre
/// toward it (the whole sphere of directions, 2, from inside).
fn cone(to: Vec3, radius: f32) -> (Vec3, f32) {
    let d2 = to.length_squared();
    let s2 = radius * radius / d2;
    if s2.is_nan() || s2 >= 1.0 {
        return (Vec3::Y, 2.0);
    }
    // 1 − √(1 − s²) without cancellation for small cones.
    (to / d2.sqrt(), s2 / (1.0 + (1.0 - s2).sqrt()))
}

/// Uniform direction in the cone around `axis` with `1 − cos θmax = h`.
fn in_cone(axis: Vec3, h: f32, u1: f32, u2: f32) -> Vec3 {
    let cos = 1.0 - u1 * h;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    let (t, b) = basis(axis);
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize_or(axis)
}

/// One photon path: light → `target.object` → specular⁺ → first diffuse hit (stored).
fn trace_photon(
    integrator: &Integrator,
    target: &Target,
    rng: &mut Rng,
    out: &mut Vec<Photon>,
    rays: &mut u64,
) {
    let light: &AreaLight = &integrator.scene.lights[target.light];
    let (u1, u2, u3, u4) = (
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
    );
    let q = light.center + (u1 - 0.5) * light.edge_u + (u2 - 0.5) * light.edge_v;
    let normal = light.normal();
    let (axis, h) = cone(target.center - q, target.radius);
    let mut dir = in_cone(axis, h, u3, u4);
    let cos_l = normal.dot(dir);
    if cos_l.is_nan() || cos_l <= 0.0 {
        return;
    }
    // Flux of the cone sample: L cos A Ω / N, Ω = 2π(1 − cos θmax).
    let mut power = light.radiance * (cos_l * light.area() * 2.0 * PI * h / target.count as f32);
    let mut origin = offset(q, normal);
    let mut medium: Option<Vec3> = None;
    let max_bounces = integrator.transport.max_specular_bounces;
    for bounce in 0..=max_bounces {
        *rays += 1;
        let Some(hit) = integrator
            .bvh
            .closest(origin, dir, 0.0, f32::INFINITY, None)
        else {
            return;
        };
        if bounce == 0 && hit.prim.object != target.object {
            return;
        }
        if let Some(sigma) = medium {
            power *= (-sigma * hit.t).exp();
        }
        let s = integrator.surface(&hit, dir);
        let material = integrator.material(hit.prim.object);
        if let Material::Diffuse { .. } = material {
            if bounce > 0 && power.is_finite() && power.max_element() > 0.0 {
                out.push(Photon {
                    p: s.p,
                    n: s.ng,
                    power,
                });
            }
            return;
        }
        if bounce == max_bounces {
            return;
        }
        let Some((w, o, d)) = integrator.specular_bounce(&s, dir, material, &mut medium, rng)
        else {
            return;
        };
        power *= w;
        if !power.is_finite() || power.max_element() <= 0.0 {
            return;
        }
        (origin, dir) = (o, d);
    }
}
