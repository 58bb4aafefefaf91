//! Materials and light transport: a distribution ray tracer with next-event estimation.
//!
//! - Lambertian: one area-light sample per hit (soft shadows) plus cosine-sampled indirect
//!   bounces, at most `max_diffuse_bounces` per path. Light reached by an indirect bounce
//!   is not counted again (the light sample already did), so emitters add their radiance
//!   only to paths without a diffuse bounce: camera rays and pure specular chains.
//! - Caustics (light → specular⁺ → diffuse, e.g. the floor lit by the teapot), which the
//!   light sample cannot find, per [`Caustics`]: by default every diffuse hit adds the
//!   irradiance of a caustic photon map ([`super::photons`]); `Paths` instead lets an
//!   emitter count when a specular bounce led to it after a diffuse one; `Off` leaves
//!   them out (tracer version 1).
//! - Mirror: the exact reflection, weighted by `schlick_fresnel(f0, n·v)`: the runtime's
//!   formula at the shading normal.
//! - Glossy: the same Fresnel weight, direction drawn from a normalised Phong lobe around
//!   the mirror direction (exponent `2/roughness⁴ − 2`, the Beckmann-equivalent).
//! - Glass: Schlick Fresnel from `f0 = ((ior − 1)/(ior + 1))²` (at the transmitted angle
//!   when leaving the denser side, 1 under total internal reflection), reflection or
//!   refraction chosen with probability F, Beer–Lambert absorption inside.
//!
//! Surfaces are two-sided except emitters, which emit on their front (winding) side only.

mod analytic;
mod camera_ray;

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::bvh::{Hit, SceneBvh};
use super::optics::{above, dielectric, offset, phong_exponent, reflect, refract};
use super::photons::PhotonMap;
use super::rng::{Rng, cosine_hemisphere, phong_lobe};
use super::transport::{Caustics, Transport};
use crate::fresnel::schlick_fresnel;
use crate::scene::{AreaLight, Material, Scene};

/// What the camera ray of one film sample saw, split the way the layers need it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Full radiance along the camera ray.
    pub beauty: Vec3,
    /// Object of the first hit.
    pub object: Option<u32>,
    pub terms: Terms,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Terms {
    /// Background or emitter: beauty only.
    None,
    /// A Lambertian first hit: all of `beauty`.
    Diffuse(Vec3),
    /// A reflective first hit: `beauty = fresnel × (local if self-hit else distant)
    /// + transmission`.
    Specular {
        fresnel: Vec3,
        /// Radiance along the reflected ray with the object itself transparent.
        distant: Vec3,
        /// Radiance along the reflected ray when its first hit is the object itself.
        local: Option<Vec3>,
        /// Glass only: `(1 − F) ×` radiance along the refracted ray.
        transmission: Vec3,
    },
}

#[derive(Clone, Copy, Debug, Default)]
struct PathState {
    diffuse: u32,
    specular: u32,
    /// Emitters count on this segment (no diffuse bounce so far).
    count_emission: bool,
    /// Absorption per metre of the medium the current segment travels through.
    medium: Option<Vec3>,
}

pub(super) use super::surface::Surface;

pub struct Integrator<'a> {
    pub(super) scene: &'a Scene,
    pub(super) bvh: &'a SceneBvh,
    pub(super) transport: Transport,
    /// The caustic photon map read at diffuse hits (`Caustics::Photons`).
    photons: Option<&'a PhotonMap>,
    /// Per object: true for the room's box (transparent to directional light).
    room: Vec<bool>,
    /// Per object: the objects its reflected rays count as local
    /// ([`Scene::local_group`]).
    local: Vec<Vec<usize>>,
}

impl<'a> Integrator<'a> {
    pub fn new(scene: &'a Scene, bvh: &'a SceneBvh, transport: Transport) -> Self {
        Integrator {
            scene,
            bvh,
            transport,
            photons: None,
            room: analytic::room_mask(scene),
            local: scene.local_groups(),
        }
    }

    /// The same integrator reading `photons` at every diffuse hit.
    pub fn with_photons<'b>(self, photons: Option<&'b PhotonMap>) -> Integrator<'b>
    where
        'a: 'b,
    {
        Integrator { photons, ..self }
    }

    /// Whether a ray reflected by `object` that hits `other` hit the
    /// reflector again (its local layer).
    pub(super) fn is_local(&self, object: u32, other: u32) -> bool {
        other == object
            || self
                .local
                .get(object as usize)
                .is_some_and(|g| g.contains(&(other as usize)))
    }

    pub(super) fn material(&self, object: u32) -> &Material {
        &self.scene.materials[self.scene.objects[object as usize].material]
    }

    pub(super) fn surface(&self, hit: &Hit, dir: Vec3) -> Surface {
        let mesh = self.scene.objects[hit.prim.object as usize].traced_mesh();
        Surface::at(mesh, hit.prim.triangle as usize, hit.bary, dir)
    }

    fn albedo(&self, albedo: Vec3, texture: Option<usize>, uv: Vec2) -> Vec3 {
        match texture.and_then(|t| self.scene.textures.get(t)) {
            Some(tex) => albedo * tex.sample_bilinear(uv).truncate(),
            None => albedo,
        }
    }

    /// One area-light sample plus the exact directional and point lights: radiance
    /// reflected by a white Lambertian surface (albedo 1).
    fn direct(&self, s: &Surface, rng: &mut Rng, rays: &mut u64) -> Vec3 {
        let area = self.area_direct(s, rng, rays);
        if self.scene.directional_lights.is_empty() && self.scene.point_lights.is_empty() {
            // Scenes without them trace exactly as before (same sums, same rays).
            return area;
        }
        area + self.analytic_direct(s, rays)
    }

    /// One area-light sample (zero without area lights).
    fn area_direct(&self, s: &Surface, rng: &mut Rng, rays: &mut u64) -> Vec3 {
        let lights = &self.scene.lights;
        let n = lights.len();
        let pick = ((rng.next_f32() * n as f32) as usize).min(n.saturating_sub(1));
        let (u1, u2) = (rng.next_f32(), rng.next_f32());
        let Some(light) = lights.get(pick) else {
            return Vec3::ZERO;
        };
        light_sample(light, s, u1, u2, n as f32, |o, d, tmax| {
            *rays += 1;
            self.bvh.occluded(o, d, 0.0, tmax)
        })
    }

    /// Radiance along a ray; also returns its first hit. `skip` makes one object transparent
    /// for this segment only (the distant layer's reflected ray).
    fn radiance(
        &self,
        origin: Vec3,
        dir: Vec3,
        skip: Option<u32>,
        rng: &mut Rng,
        state: PathState,
        rays: &mut u64,
    ) -> (Vec3, Option<Hit>) {
        *rays += 1;
        match self.bvh.closest(origin, dir, 0.0, f32::INFINITY, skip) {
            None => (self.transport.background, None),
            Some(hit) => (self.shade(hit, dir, rng, state, rays), Some(hit)),
        }
    }

    /// Radiance along a ray reflected by `object` with every object of its
    /// local group transparent for this segment (the distant layer's ray).
    fn radiance_past_group(
        &self,
        origin: Vec3,
        dir: Vec3,
        object: u32,
        rng: &mut Rng,
        state: PathState,
        rays: &mut u64,
    ) -> Vec3 {
        let group = self.local.get(object as usize).map_or(&[][..], |g| &g[..]);
        if group.len() <= 1 {
            // One reflector: the same traversal as always (keys and pixels kept).
            return self.radiance(origin, dir, Some(object), rng, state, rays).0;
        }
        *rays += 1;
        let past = |o: u32| !group.contains(&(o as usize));
        match self
            .bvh
            .closest_where(origin, dir, 0.0, f32::INFINITY, past)
        {
            None => self.transport.background,
            Some(hit) => self.shade(hit, dir, rng, state, rays),
        }
    }

    /// Radiance leaving `hit` towards the origin of the ray `dir` that found it.
    fn shade(
        &self,
        mut hit: Hit,
        mut dir: Vec3,
        rng: &mut Rng,
        mut state: PathState,
        rays: &mut u64,
    ) -> Vec3 {
        let tr = self.transport;
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        loop {
            if let Some(sigma) = state.medium {
                beta *= (-sigma * hit.t).exp();
            }
            let s = self.surface(&hit, dir);
            let material = self.material(hit.prim.object);
            let next = match *material {
                Material::Emissive { radiance } => {
                    if state.count_emission && s.front {
                        l += beta * radiance;
                    }
                    None
                }
                Material::Diffuse { albedo, texture } => {
                    let albedo = self.albedo(albedo, texture, s.uv);
                    let caustic = self.caustic(&s, state.diffuse > 0);
                    l += beta * albedo * (self.direct(&s, rng, rays) + caustic);
                    if state.diffuse >= tr.max_diffuse_bounces {
                        None
                    } else {
                        state.diffuse += 1;
                        state.count_emission = false;
                        state.medium = None;
                        beta *= albedo;
                        let d = cosine_hemisphere(s.ns, rng.next_f32(), rng.next_f32());
                        Some((offset(s.p, s.ng), above(d, s.ng)))
                    }
                }
                Material::Mirror { .. } | Material::Glossy { .. } | Material::Glass { .. } => {
                    if state.specular >= tr.max_specular_bounces {
                        None
                    } else {
                        state.specular += 1;
                        // Emission found through a specular chain cannot be light-sampled.
                        state.count_emission |= tr.caustics == Caustics::Paths;
                        self.specular_bounce(&s, dir, material, &mut state.medium, rng)
                            .map(|(w, o, d)| {
                                beta *= w;
                                (o, d)
                            })
                    }
                }
            };
            let Some((o, d)) = next else { break };
            if beta.max_element() <= 0.0 {
                break;
            }
            *rays += 1;
            match self.bvh.closest(o, d, 0.0, f32::INFINITY, None) {
                None => {
                    l += beta * tr.background;
                    break;
                }
                Some(h) => {
                    hit = h;
                    dir = d;
                }
            }
        }
        l
    }

    /// One bounce off a reflective material at `s`: `(weight, origin, direction)` of the
    /// next segment. Mirror and glossy reflect, weighted by Fresnel, into air; glass
    /// reflects or refracts with probability F and updates `medium`. Camera and photon
    /// paths share it, so both follow the same specular chains.
    pub(super) fn specular_bounce(
        &self,
        s: &Surface,
        dir: Vec3,
        material: &Material,
        medium: &mut Option<Vec3>,
        rng: &mut Rng,
    ) -> Option<(Vec3, Vec3, Vec3)> {
        match *material {
            Material::Mirror { .. } | Material::Glossy { .. } => {
                *medium = None;
                let (f, r) = self.specular(s, dir, material, rng);
                Some((f, offset(s.p, s.ng), r))
            }
            Material::Glass { ior, absorption } => {
                let cos_i = s.ns.dot(-dir).clamp(0.0, 1.0);
                let (f, cos_t) = dielectric(ior, cos_i, s.front);
                match cos_t {
                    Some(cos_t) if rng.next_f32() >= f => {
                        *medium = s.front.then_some(absorption);
                        let t = refract(dir, s.ns, ior, s.front, cos_i, cos_t);
                        Some((Vec3::ONE, offset(s.p, -s.ng), t))
                    }
                    _ => Some((Vec3::ONE, offset(s.p, s.ng), reflect(dir, s.ns))),
                }
            }
            Material::Diffuse { .. } | Material::Emissive { .. } => None,
        }
    }

    /// Radiance a white Lambertian surface reflects of the caustic photon map's irradiance.
    /// Hits reached by a diffuse bounce (`bounced`) read the coarse map: they land all over
    /// the scene, where the fine one would miss the cache, and the bounce blurs the caustic
    /// anyway (teapot sample 30: floor within 0.5% of the fine map's, per band).
    fn caustic(&self, s: &Surface, bounced: bool) -> Vec3 {
        let Some(map) = self.photons else {
            return Vec3::ZERO;
        };
        let e = if bounced {
            map.coarse_irradiance(s.p, s.ng)
        } else {
            map.irradiance(s.p, s.ng)
        };
        e / PI
    }

    /// Fresnel weight and reflected direction of a mirror or glossy surface.
    fn specular(&self, s: &Surface, dir: Vec3, material: &Material, rng: &mut Rng) -> (Vec3, Vec3) {
        let cos = s.ns.dot(-dir);
        let mirror = reflect(dir, s.ns).normalize_or(s.ng);
        match *material {
            Material::Mirror { f0 } => (schlick_fresnel(f0, cos), above(mirror, s.ng)),
            Material::Glossy { f0, roughness } => {
                let d = phong_lobe(
                    mirror,
                    phong_exponent(roughness),
                    rng.next_f32(),
                    rng.next_f32(),
                );
                (schlick_fresnel(f0, cos), above(d, s.ng))
            }
            _ => (Vec3::ZERO, mirror),
        }
    }

    /// Radiance leaving `hit` back along `dir`, for a camera path that reached
    /// it through `specular` specular bounces and no diffuse one (so emitters
    /// count): what the glass targets' exit rays see.
    pub fn radiance_at(
        &self,
        hit: Hit,
        dir: Vec3,
        specular: u32,
        rng: &mut Rng,
        rays: &mut u64,
    ) -> Vec3 {
        let state = PathState {
            specular,
            count_emission: true,
            ..PathState::default()
        };
        self.shade(hit, dir, rng, state, rays)
    }

    /// First hit point of a ray and the mirror direction there (shading normal): the
    /// geometry every reflective layer is built on, exposed for checks.
    pub fn reflect_once(&self, origin: Vec3, dir: Vec3) -> Option<(Vec3, Vec3)> {
        let hit = self.bvh.closest(origin, dir, 0.0, f32::INFINITY, None)?;
        let s = self.surface(&hit, dir);
        Some((s.p, above(reflect(dir, s.ns).normalize_or(s.ng), s.ng)))
    }
}

/// Radiance from a uniform point `(u1, u2)` on `light` reaching Lambertian surface `s` with
/// albedo 1, divided by the light-choice probability `1/n_lights`; `occluded(origin, dir,
/// tmax)` is the shadow test.
fn light_sample(
    light: &AreaLight,
    s: &Surface,
    u1: f32,
    u2: f32,
    n_lights: f32,
    occluded: impl FnOnce(Vec3, Vec3, f32) -> bool,
) -> Vec3 {
    let q = light.center + (u1 - 0.5) * light.edge_u + (u2 - 0.5) * light.edge_v;
    let o = offset(s.p, s.ng);
    let to = q - o;
    let d2 = to.length_squared();
    if d2.is_nan() || d2 <= 1e-12 {
        return Vec3::ZERO;
    }
    let d = d2.sqrt();
    let wi = to / d;
    let cos_s = s.ns.dot(wi);
    let cos_l = -light.normal().dot(wi);
    if cos_s <= 0.0 || cos_l <= 0.0 || s.ng.dot(wi) <= 0.0 {
        return Vec3::ZERO;
    }
    // Stop short of the light's own quad.
    if occluded(o, wi, d * (1.0 - 1e-4)) {
        return Vec3::ZERO;
    }
    light.radiance * (cos_s * cos_l * light.area() * n_lights / (d2 * PI))
}
