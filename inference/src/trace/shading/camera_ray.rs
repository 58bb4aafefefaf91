//! The camera ray of one film sample, split into the terms the layers need:
//! diffuse first hits whole, reflective ones into Fresnel weight, distant
//! and local reflected radiance, and glass's transmission.

use glam::Vec3;

use super::{Integrator, PathState, Sample, Surface, Terms};
use crate::scene::Material;
use crate::trace::optics::{dielectric, offset, reflect, refract};
use crate::trace::rng::Rng;

impl Integrator<'_> {
    /// The camera ray of one film sample. `distant_rng` drives the extra distant-layer ray
    /// so that the beauty path's random numbers do not depend on whether it is traced.
    pub fn sample(
        &self,
        origin: Vec3,
        dir: Vec3,
        rng: &mut Rng,
        distant_rng: &mut Rng,
        rays: &mut u64,
    ) -> Sample {
        *rays += 1;
        let Some(hit) = self.bvh.closest(origin, dir, 0.0, f32::INFINITY, None) else {
            return Sample {
                beauty: self.transport.background,
                object: None,
                terms: Terms::None,
            };
        };
        let object = hit.prim.object;
        let camera = PathState {
            count_emission: true,
            ..PathState::default()
        };
        let material = self.material(object);
        if matches!(
            material,
            Material::Diffuse { .. } | Material::Emissive { .. }
        ) {
            let l = self.shade(hit, dir, rng, camera, rays);
            let terms = match material {
                Material::Diffuse { .. } => Terms::Diffuse(l),
                _ => Terms::None,
            };
            return Sample {
                beauty: l,
                object: Some(object),
                terms,
            };
        }

        let s = self.surface(&hit, dir);
        let after = PathState {
            specular: 1,
            ..camera
        };
        let (fresnel, r, transmission) = self.camera_bounce(&s, dir, material, rng, after, rays);
        let o = offset(s.p, s.ng);
        let (l_r, first) = self.radiance(o, r, None, rng, after, rays);
        // A hit on the object or a reflector touching it (lid and body) is local.
        let self_hit = first.is_some_and(|h| self.is_local(object, h.prim.object));
        // Where the reflected ray misses them, "passing through them" changes nothing.
        let distant = if self_hit {
            self.radiance_past_group(o, r, object, distant_rng, after, rays)
        } else {
            l_r
        };
        Sample {
            beauty: fresnel * l_r + transmission,
            object: Some(object),
            terms: Terms::Specular {
                fresnel,
                distant,
                local: self_hit.then_some(l_r),
                transmission,
            },
        }
    }

    /// The Fresnel weight, the reflected direction and the transmitted
    /// radiance of the camera ray's bounce on a non-diffuse surface (glass
    /// refracts and traces the transmitted path here).
    fn camera_bounce(
        &self,
        s: &Surface,
        dir: Vec3,
        material: &Material,
        rng: &mut Rng,
        after: PathState,
        rays: &mut u64,
    ) -> (Vec3, Vec3, Vec3) {
        match *material {
            Material::Glass { ior, absorption } => {
                let cos_i = s.ns.dot(-dir).clamp(0.0, 1.0);
                let (f, cos_t) = dielectric(ior, cos_i, s.front);
                let transmission = match cos_t {
                    Some(cos_t) if f < 1.0 => {
                        let t = refract(dir, s.ns, ior, s.front, cos_i, cos_t);
                        let inside = PathState {
                            medium: s.front.then_some(absorption),
                            ..after
                        };
                        let (l_t, _) =
                            self.radiance(offset(s.p, -s.ng), t, None, rng, inside, rays);
                        (1.0 - f) * l_t
                    }
                    _ => Vec3::ZERO,
                };
                (Vec3::splat(f), reflect(dir, s.ns), transmission)
            }
            _ => {
                let (f, r) = self.specular(s, dir, material, rng);
                (f, r, Vec3::ZERO)
            }
        }
    }
}
