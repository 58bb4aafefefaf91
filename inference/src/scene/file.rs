//! The scene file as written by hand (TOML), before validation. Field docs live in
//! `assets/scenes/teapot.toml`; every table rejects unknown keys so typos surface.

use std::collections::BTreeMap;

use serde::Deserialize;

use super::material::EmLayer;
use super::texture::Pattern;
use crate::teapot::TeapotPart;

pub type V3 = [f32; 3];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Defaults to the file stem.
    pub name: Option<String>,
    pub camera: CameraFile,
    pub orbit: OrbitFile,
    pub room: RoomFile,
    #[serde(default)]
    pub lights: Vec<LightFile>,
    /// Optional; absent in the shipped scenes.
    #[serde(default)]
    pub directional_lights: Vec<DirectionalLightFile>,
    #[serde(default)]
    pub point_lights: Vec<PointLightFile>,
    /// Sorted by name; a material's index in `Scene::materials` follows this order.
    pub materials: BTreeMap<String, MaterialFile>,
    #[serde(default)]
    pub objects: Vec<ObjectFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub fov_y_deg: f32,
    pub near: f32,
    pub far: f32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitFile {
    pub center: V3,
    pub radius: f32,
    pub height: f32,
    /// Evenly spaced lines: `samples` azimuths `step_deg` apart from
    /// `start_deg` [defaults 0°, 1°, 100]; or `azimuths_deg`, each given.
    pub start_deg: Option<f32>,
    pub step_deg: Option<f32>,
    pub samples: Option<u32>,
    /// Azimuth lines placed where the scene needs them (`engine place`),
    /// increasing; replaces start_deg, step_deg and samples.
    pub azimuths_deg: Option<Vec<f32>>,
    /// Elevation rings of the 2D viewpoint space [1: the 1D orbit],
    /// `ring_step_deg` apart above the orbit plane [10°]; or
    /// `ring_elevations_deg`, each given (the first 0, increasing).
    pub rings: Option<u32>,
    pub ring_step_deg: Option<f32>,
    /// Rings placed where the scene needs them (`engine place --rings`).
    pub ring_elevations_deg: Option<Vec<f32>>,
    /// The rings above the first keep every this-many azimuth lines (and
    /// the last) [1: every line].
    pub ring_line_every: Option<u32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoomFile {
    pub min: V3,
    pub max: V3,
    /// Material names.
    pub floor: String,
    pub walls: String,
    pub ceiling: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightFile {
    pub name: String,
    pub center: V3,
    pub edge_u: V3,
    pub edge_v: V3,
    pub radiance: V3,
}

/// `[[directional_lights]]`: `to_light` points toward the light (normalised on load).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionalLightFile {
    pub name: String,
    pub to_light: V3,
    pub irradiance: V3,
}

/// `[[point_lights]]`: an isotropic point light inside the room.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLightFile {
    pub name: String,
    pub position: V3,
    pub intensity: V3,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum MaterialFile {
    Diffuse {
        albedo: V3,
        texture: Option<TextureFile>,
    },
    Mirror {
        f0: V3,
    },
    Glossy {
        f0: V3,
        roughness: f32,
    },
    Glass {
        ior: f32,
        #[serde(default)]
        absorption: V3,
    },
    Emissive {
        radiance: V3,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureFile {
    pub pattern: Pattern,
    pub colors: [V3; 2],
    /// World-space size of one texture repeat, metres.
    pub tile_size: f32,
    #[serde(default = "default_line_width")]
    pub line_width: f32,
    #[serde(default = "default_texture_resolution")]
    pub resolution: u32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectFile {
    pub name: String,
    pub mesh: MeshFile,
    pub material: String,
    #[serde(default)]
    pub transform: TransformFile,
    pub em: Option<EmFile>,
    pub glass: Option<GlassFile>,
}

/// One of `{ generator = "newell_teapot", segments = 25, part = "whole" }`,
/// `{ file = "path/relative/to/the/scene/file.glb" }` (.obj, .gltf or .glb) or
/// `{ obj = "….obj" }` (the older spelling); checked after parsing so the
/// error can say which keys clash.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    pub generator: Option<String>,
    pub segments: Option<u32>,
    /// The tracer's own, finer tessellation of the same surface.
    pub trace_segments: Option<u32>,
    pub part: Option<TeapotPart>,
    pub obj: Option<String>,
    pub file: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformFile {
    #[serde(default)]
    pub translate: V3,
    #[serde(default = "one")]
    pub scale: f32,
    #[serde(default)]
    pub rotate_y_deg: f32,
}

impl Default for TransformFile {
    fn default() -> Self {
        TransformFile {
            translate: [0.0; 3],
            scale: 1.0,
            rotate_y_deg: 0.0,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmFile {
    #[serde(default = "default_em_resolution")]
    pub resolution: u32,
    #[serde(default = "default_layers")]
    pub layers: Vec<EmLayer>,
    #[serde(default)]
    pub lod_bias: f32,
    #[serde(default)]
    pub neighbour_weight: f32,
    #[serde(default)]
    pub local_bound: f32,
    #[serde(default)]
    pub display_weight: bool,
    pub neighbour_deg: Option<f32>,
    #[serde(default)]
    pub neighbour_above_deg: Vec<f32>,
    pub neighbour_above_spacing_deg: Option<f32>,
    pub neighbour_above_weight: Option<f32>,
}

/// `[objects.glass]`; see `scene::glass::GlassSettings` for the meanings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlassFile {
    pub resolution: Option<u32>,
    pub shells: Option<u32>,
    pub tau: Option<f32>,
    pub views: Option<u32>,
    pub view_spread_deg: Option<f32>,
    pub shell_every: Option<u32>,
}

fn default_line_width() -> f32 {
    0.04
}
fn default_texture_resolution() -> u32 {
    512
}
fn default_em_resolution() -> u32 {
    256
}
fn default_layers() -> Vec<EmLayer> {
    vec![EmLayer::Distant, EmLayer::Local]
}
fn one() -> f32 {
    1.0
}
