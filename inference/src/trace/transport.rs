//! What the integrator counts: path limits, the environment's radiance and how caustics
//! are found.

use glam::Vec3;

/// Path limits and the radiance of rays that leave the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transport {
    /// Radiance of rays that hit nothing (a uniform environment; zero in a closed room).
    pub background: Vec3,
    pub max_diffuse_bounces: u32,
    /// Mirror, glossy and glass bounces per path.
    pub max_specular_bounces: u32,
    pub caustics: Caustics,
}

impl Default for Transport {
    fn default() -> Self {
        Transport {
            background: Vec3::ZERO,
            max_diffuse_bounces: 2,
            max_specular_bounces: 8,
            caustics: Caustics::default(),
        }
    }
}

/// How light that reaches a diffuse surface through mirrors, glossy or glass objects
/// (light → specular⁺ → diffuse, e.g. the floor lit by the teapot) is counted. Light
/// sampling cannot find it: the light is only reached through the reflector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Caustics {
    /// Not counted (tracer version 1).
    Off,
    /// Unbiased but noisy: a diffuse bounce that reaches an emitter through at least one
    /// specular bounce adds its emission.
    Paths,
    /// A photon map ([`super::photons`]): about `photons` paths from the lights toward
    /// the reflective objects, irradiance estimated over `radius` metres. No noise per
    /// sample; blurred by `radius`.
    Photons { photons: u32, radius: f32 },
}

impl Default for Caustics {
    fn default() -> Self {
        Caustics::Photons {
            photons: DEFAULT_PHOTONS,
            radius: DEFAULT_PHOTON_RADIUS,
        }
    }
}

/// Photon paths per image by default (see `inference/NOTES-caustics.md`).
pub const DEFAULT_PHOTONS: u32 = 250_000;
/// Photon-gathering radius by default, metres.
pub const DEFAULT_PHOTON_RADIUS: f32 = 0.04;
