//! The room as the reflector sees it, traced as a cylindrical panorama from the
//! reflector's EM origin under one moving light at a time.
//!
//! The relit scene is the scene with its area lights dark (their quads stay, as
//! black geometry) and exactly one directional or point light
//! ([`crate::scene::light`]): the relightable environment holds the light the
//! moving light adds. Primary rays pass through the reflector (it does not see
//! itself from inside, as the distant layer); it still shadows and reflects for
//! every later bounce. Caustics are off.

use glam::Vec3;
use rayon::prelude::*;

use crate::scene::{DirectionalLight, Material, PointLight, Scene};
use crate::trace::bvh::Hit;
use crate::trace::rng::Rng;
use crate::trace::{Caustics, Integrator, SceneBvh, Transport};

/// Cylindrical panorama: column x is azimuth φ = 2π(x + ½)/width from +x toward
/// +z (the SH basis's φ), rows span heights ±π·height/width on the unit cylinder
/// (square pixels at the horizon), y down.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Panorama {
    pub width: u32,
    pub height: u32,
}

impl Panorama {
    pub fn texels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Unit view direction through film point `(fx, fy)` (pixel centres at +½).
    pub fn direction(&self, fx: f32, fy: f32) -> Vec3 {
        let phi = std::f32::consts::TAU * fx / self.width as f32;
        let h = std::f32::consts::PI * (self.height as f32 - 2.0 * fy) / self.width as f32;
        Vec3::new(phi.cos(), h, phi.sin()).normalize()
    }
}

/// How each panorama is traced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PanoramaSettings {
    pub panorama: Panorama,
    pub spp: u32,
    pub seed: u64,
    /// Diffuse bounces after the first hit (indirect light).
    pub bounces: u32,
}

/// The one light a panorama is traced under.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MovingLight {
    /// Irradiance 1 (per channel) from unit direction `to_light`.
    Directional(Vec3),
    Point {
        position: Vec3,
        intensity: Vec3,
    },
}

/// The relit scene, its BVH, the reflector and the panorama's origin.
pub struct RelightScene {
    scene: Scene,
    bvh: SceneBvh,
    /// Object indices of the reflector, transparent to primary rays: the
    /// first object with environment maps and the parts its local layer
    /// groups with it (`teapot_split`'s body and lid,
    /// [`Scene::local_group`]), so a panorama seen from inside the teapot
    /// sees the room, not the lid from below.
    pub reflector: Vec<u32>,
    pub origin: Vec3,
}

/// Where `scene`'s panoramas are seen from: the area-weighted centroid of
/// the first object with environment maps (the static EM's origin), else
/// the orbit centre.
pub fn panorama_origin(scene: &Scene) -> Vec3 {
    let reflector = scene.objects.iter().find(|o| o.em.is_some());
    reflector.map_or(scene.orbit.center, |r| r.mesh.area_weighted_centroid())
}

impl RelightScene {
    /// From `scene`: the first object with environment maps is the reflector and
    /// its area-weighted centroid (the static EM's origin) the panorama's origin;
    /// without one, the orbit centre.
    pub fn new(scene: &Scene) -> RelightScene {
        let mut dark = scene.clone();
        for l in &dark.lights {
            if let Some(i) = dark.material_index(&l.name)
                && let Some(Material::Emissive { radiance }) = dark.materials.get_mut(i)
            {
                *radiance = Vec3::ZERO;
            }
        }
        dark.lights.clear();
        dark.directional_lights.clear();
        dark.point_lights.clear();
        let reflector = scene.objects.iter().position(|o| o.em.is_some());
        let group = reflector.map_or(Vec::new(), |r| scene.local_group(r));
        let origin = panorama_origin(scene);
        RelightScene {
            bvh: SceneBvh::build(&dark),
            scene: dark,
            reflector: group.into_iter().map(|o| o as u32).collect(),
            origin,
        }
    }

    /// The scene as traced under `light` (for checks and references).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Radiance per texel (row-major) under `light`.
    pub fn trace(&mut self, light: MovingLight, settings: &PanoramaSettings) -> Vec<Vec3> {
        self.scene.directional_lights.clear();
        self.scene.point_lights.clear();
        match light {
            MovingLight::Directional(to_light) => {
                self.scene.directional_lights.push(DirectionalLight {
                    name: "moving".into(),
                    to_light: to_light.normalize_or(Vec3::Y),
                    irradiance: Vec3::ONE,
                })
            }
            MovingLight::Point {
                position,
                intensity,
            } => self.scene.point_lights.push(PointLight {
                name: "moving".into(),
                position,
                intensity,
            }),
        }
        let transport = Transport {
            max_diffuse_bounces: settings.bounces,
            caustics: Caustics::Off,
            ..Transport::default()
        };
        let integrator = Integrator::new(&self.scene, &self.bvh, transport);
        let p = settings.panorama;
        let mut out = vec![Vec3::ZERO; p.texels()];
        out.par_chunks_mut(p.width as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, texel) in row.iter_mut().enumerate() {
                    let pixel = (y * p.width as usize + x) as u64;
                    let mut sum = Vec3::ZERO;
                    let mut rays = 0u64;
                    for s in 0..settings.spp {
                        // The same streams under every light: noise correlated
                        // across light directions, so it projects smoothly.
                        let mut rng = Rng::new(settings.seed, pixel, s, 0);
                        let (fx, fy) = (x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
                        let d = p.direction(fx, fy);
                        if let Some(hit) = self.first_hit(d) {
                            sum += integrator.radiance_at(hit, d, 0, &mut rng, &mut rays);
                        }
                    }
                    *texel = sum / settings.spp.max(1) as f32;
                }
            });
        out
    }

    /// What a ray from the origin along `dir` meets first, through the
    /// reflector's parts.
    fn first_hit(&self, dir: Vec3) -> Option<Hit> {
        let seen = |o: u32| !self.reflector.contains(&o);
        self.bvh
            .closest_where(self.origin, dir, 0.0, f32::INFINITY, seen)
    }

    /// World position of each texel centre's first hit (through the reflector);
    /// a ray that leaves the scene gets a point 10⁶ m away.
    pub fn positions(&self, panorama: Panorama) -> Vec<Vec3> {
        (0..panorama.texels())
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % panorama.width as usize, i / panorama.width as usize);
                let d = panorama.direction(x as f32 + 0.5, y as f32 + 0.5);
                let t = self.first_hit(d).map_or(1e6, |h| h.t);
                self.origin + d * t
            })
            .collect()
    }
}
