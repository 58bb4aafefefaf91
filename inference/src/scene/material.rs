//! Surface materials and per-object environment-map settings.

use glam::Vec3;

/// Reflectance model of a surface. The tracer and the runtime share these parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Lambertian; `texture` (index into `Scene::textures`) multiplies `albedo`.
    Diffuse {
        albedo: Vec3,
        texture: Option<usize>,
    },
    /// Perfect specular reflector with Schlick Fresnel from `f0`.
    Mirror { f0: Vec3 },
    /// Rough specular reflector; `roughness` in (0, 1].
    Glossy { f0: Vec3, roughness: f32 },
    /// Dielectric with Beer–Lambert `absorption` per metre and channel.
    Glass { ior: f32, absorption: Vec3 },
    /// Light source surface.
    Emissive { radiance: Vec3 },
}

/// Per-object environment-map settings (PEM layers).
#[derive(Clone, Debug, PartialEq)]
pub struct EmSettings {
    /// Cube face edge length in texels.
    pub resolution: u32,
    pub layers: Vec<EmLayer>,
    /// Added to the level of detail of every lookup into the maps, in the
    /// probe renders the maps are inferred through and in playback alike.
    /// The hardware's isotropic level blurs a curved mirror's reflection
    /// beyond what the tracer's pixel (a box of 16 paths) averages; a
    /// negative bias reads finer levels.
    pub lod_bias: f32,
    /// Weight of each neighbouring sample's view (azimuth ± 1 on the same
    /// ring, its own trace) stacked into a sample's EM solve; 0 solves each
    /// sample from its own view alone. Sharp maps fit to one view generalize
    /// poorly to the views between samples; their neighbours constrain
    /// the texels only nearby views reach.
    pub neighbour_weight: f32,
    /// Weight of a penalty on the local layer's texels outside the range
    /// of a premultiplied layer (colour ≥ 0, 0 ≤ α ≤ 1), zero inside it;
    /// 0 = off. The free fit lets texels no view pins down alternate far
    /// outside it, which plays as speckle (README, "Where the whole
    /// frame's remaining error is").
    pub local_bound: f32,
    /// Weight each pixel's rows by the slope of the display transform at
    /// the traced pixel (sRGB, clamped to [0, 1]): the solve then fits
    /// the errors a person sees in the PNG, not linear radiance, where a
    /// dark rim next to a bright highlight weighs almost nothing.
    pub display_weight: bool,
    /// With stacking on, the stacked views lie this many degrees either
    /// side of each sample on its ring, traced for the purpose, instead of
    /// at the neighbouring samples. A placed orbit's neighbours lie 1–25°
    /// apart; views that far off fit a map worse than they teach it.
    pub neighbour_deg: Option<f32>,
    /// With stacking on, also the views this many degrees above (negative:
    /// below) each sample at its azimuth, traced for the purpose. A 1D
    /// orbit's sample serves every elevation at its azimuth; views off the
    /// plane constrain the texels only they reach.
    pub neighbour_above_deg: Vec<f32>,
    /// With views above, put them on an azimuth grid this many degrees
    /// apart (from the orbit's first azimuth) instead of at every sample:
    /// each sample stacks the grid views nearest its azimuth, so the
    /// samples around one share its trace and its probe renders.
    pub neighbour_above_spacing_deg: Option<f32>,
    /// With views above, their weight in the solves instead of
    /// `neighbour_weight`: the views above pull a sample's maps toward
    /// what the eye sees off the plane, at a cost on the plane.
    pub neighbour_above_weight: Option<f32>,
}

/// The LOD biases a scene may ask for.
pub const LOD_BIASES: std::ops::RangeInclusive<f32> = -4.0..=2.0;
/// The local layer's bound weights a scene may ask for.
pub const LOCAL_BOUNDS: std::ops::RangeInclusive<f32> = 0.0..=1.0e4;
/// The neighbour weights a scene may ask for.
pub const NEIGHBOUR_WEIGHTS: std::ops::RangeInclusive<f32> = 0.0..=1.0;
/// The offsets of stacked views a scene may ask for, degrees.
pub const NEIGHBOUR_DEGS: std::ops::RangeInclusive<f32> = 0.01..=45.0;
/// The elevations of stacked views above a sample a scene may ask for,
/// degrees (not 0: that is the sample's own view).
pub const NEIGHBOUR_ABOVE_DEGS: std::ops::RangeInclusive<f32> = -45.0..=45.0;
/// At most this many views above each sample.
pub const NEIGHBOUR_ABOVE_MAX: usize = 4;
/// The weights of views above a scene may ask for (not 0: the views would
/// be traced for nothing).
pub const NEIGHBOUR_ABOVE_WEIGHTS: std::ops::RangeInclusive<f32> = 0.01..=1.0;
/// The azimuth spacings of shared views above a scene may ask for, degrees.
pub const NEIGHBOUR_ABOVE_SPACINGS: std::ops::RangeInclusive<f32> = 0.01..=90.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EmLayer {
    /// Box aligned with the room: what the reflector sees of its surroundings.
    Distant,
    /// Ellipsoid around the object: its self-reflections.
    Local,
}

impl Default for EmSettings {
    fn default() -> Self {
        EmSettings {
            resolution: 256,
            layers: vec![EmLayer::Distant, EmLayer::Local],
            lod_bias: 0.0,
            neighbour_weight: 0.0,
            local_bound: 0.0,
            display_weight: false,
            neighbour_deg: None,
            neighbour_above_deg: Vec::new(),
            neighbour_above_spacing_deg: None,
            neighbour_above_weight: None,
        }
    }
}

/// EM sizes playback and inference support (cube face edge, powers of two).
pub const EM_RESOLUTIONS: std::ops::RangeInclusive<u32> = 4..=2048;
