//! Directional and point lights: delta lights, so one exact shadow ray each per
//! diffuse hit and no noise of their own. Caustics they would cast through the
//! reflectors are not counted (the photon map shoots from area lights only).

use glam::Vec3;
use std::f32::consts::PI;

use super::{Integrator, Surface};
use crate::scene::Scene;
use crate::scene::light::ROOM_OBJECTS;
use crate::trace::optics::offset;

/// Per object of `scene`: is it one of the room's box objects?
pub(super) fn room_mask(scene: &Scene) -> Vec<bool> {
    scene
        .objects
        .iter()
        .map(|o| ROOM_OBJECTS.contains(&o.name.as_str()))
        .collect()
}

/// Radiance a white Lambertian surface with normal `n` (geometric `ng`) reflects
/// of irradiance `e` arriving from unit direction `wi`: `e·cos/π`, zero from behind.
fn lambert(n: Vec3, ng: Vec3, wi: Vec3, e: Vec3) -> Option<Vec3> {
    let cos = n.dot(wi);
    (cos > 0.0 && ng.dot(wi) > 0.0).then(|| e * (cos / PI))
}

impl Integrator<'_> {
    /// Every directional and point light's contribution at `s` (albedo 1).
    pub(super) fn analytic_direct(&self, s: &Surface, rays: &mut u64) -> Vec3 {
        let o = offset(s.p, s.ng);
        let mut sum = Vec3::ZERO;
        for l in &self.scene.directional_lights {
            let Some(c) = lambert(s.ns, s.ng, l.to_light, l.irradiance) else {
                continue;
            };
            *rays += 1;
            let blocks = |object: u32| !self.room.get(object as usize).copied().unwrap_or(false);
            if !self
                .bvh
                .occluded_where(o, l.to_light, 0.0, f32::MAX, blocks)
            {
                sum += c;
            }
        }
        for l in &self.scene.point_lights {
            let to = l.position - o;
            let d2 = to.length_squared();
            if d2.is_nan() || d2 <= 1e-12 {
                continue;
            }
            let d = d2.sqrt();
            let wi = to / d;
            let Some(c) = lambert(s.ns, s.ng, wi, l.intensity / d2) else {
                continue;
            };
            *rays += 1;
            if !self.bvh.occluded(o, wi, 0.0, d * (1.0 - 1e-4)) {
                sum += c;
            }
        }
        sum
    }
}
