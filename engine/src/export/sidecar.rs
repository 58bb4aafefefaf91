//! `maps.json`, what another engine needs beside the KTX2 files to play
//! them: the viewpoint of every sample (orbit azimuth and elevation, eye
//! position) and, per map, its kind and the EM geometry its cube is
//! looked up on. Positions are in the scene file's world space (right
//! handed, y up).
//!
//! A cube map's lookup, as this engine does it (PEM paper §3–4): reflect
//! the view ray at the surface point `p`, intersect the reflected ray with
//! the map's `geometry` (where it leaves the box or ellipsoid), and sample
//! the cube in direction `hit − lookup_origin` (a ray that misses falls
//! back to its own direction). `sphere_at_infinity` samples the reflected
//! direction itself, with the hardware's trilinear level of detail plus
//! `lod_bias` (the maps were inferred for that lookup). Between two
//! samples, blend the two nearest by azimuth; the local layer is
//! premultiplied RGBA composited over the distant one.

use crate::compile::infer::Job;
use crate::export::file_name;
use crate::maps::{MapLayer, MapSpec};
use inference::em_geometry::EmGeometry;
use inference::scene::Scene;
use serde::Serialize;
use std::collections::BTreeMap;

/// Bumped when a field changes meaning.
pub const SIDECAR_VERSION: u32 = 1;

#[derive(Serialize)]
pub struct Sidecar {
    pub format: &'static str,
    pub version: u32,
    pub scene: String,
    pub scene_file: String,
    pub vk_format: &'static str,
    /// Face order of the cube maps' KTX2 data (Vulkan's).
    pub face_order: [&'static str; 6],
    pub orbit: OrbitJson,
    pub maps: Vec<MapJson>,
    pub samples: Vec<SampleJson>,
}

/// The viewpoint space: `azimuth_lines` azimuths per ring, `rings`
/// elevations above the orbit plane; sample `k` is azimuth line
/// `k % azimuth_lines` of ring `k / azimuth_lines`, unless the rings above
/// the first keep every `ring_line_every`-th line only (and the last),
/// numbered after the first ring's (`samples` lists every eye).
#[derive(Serialize)]
pub struct OrbitJson {
    pub center: [f32; 3],
    pub radius: f32,
    pub height: f32,
    pub start_deg: f32,
    pub step_deg: f32,
    pub azimuth_lines: u32,
    /// The lines' azimuths when placed unevenly (`[orbit] azimuths_deg`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub azimuths_deg: Option<Vec<f32>>,
    pub rings: u32,
    pub ring_step_deg: f32,
    /// The rings' elevations when placed unevenly (`[orbit] ring_elevations_deg`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ring_elevations_deg: Option<Vec<f32>>,
    /// Present when the rings above the first skip lines.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ring_line_every: Option<u32>,
}

#[derive(Serialize)]
pub struct MapJson {
    /// `<object>.<layer>`, as in the file names.
    pub name: String,
    pub object: String,
    /// `distant`, `local` or `ptm` (a texture on the object's atlas).
    pub layer: &'static str,
    /// `cube` (6 faces) or `2d`.
    pub kind: &'static str,
    /// Base level's edge in texels.
    pub size: u32,
    pub levels: u32,
    /// Channels the inference solved for (3: A is written as 1).
    pub inferred_channels: usize,
    /// `premultiplied` (the local layer) or `opaque`.
    pub alpha: &'static str,
    /// Where the cube is looked up (absent for a PTM).
    pub em: Option<EmJson>,
    /// A PTM's mesh with its atlas coordinates, beside the maps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas: Option<String>,
}

#[derive(Serialize)]
pub struct EmJson {
    /// `box`, `ellipsoid` or `sphere_at_infinity`.
    pub geometry: &'static str,
    /// The geometry's centre (the box's middle, the ellipsoid's centre).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub center: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub box_min: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub box_max: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radii: Option<[f32; 3]>,
    /// Cube direction = hit − lookup_origin (the reflector's area-weighted centroid).
    pub lookup_origin: [f32; 3],
    /// Added to the level of detail of every lookup (as GLSL's
    /// `texture(…, bias)`).
    pub lod_bias: f32,
}

#[derive(Serialize)]
pub struct SampleJson {
    pub index: u32,
    pub azimuth_deg: f32,
    /// Above the orbit plane, seen from the orbit's centre.
    pub elevation_deg: f32,
    pub eye: [f32; 3],
    /// Map name → KTX2 file name (beside this file).
    pub files: BTreeMap<String, String>,
}

impl Sidecar {
    pub fn new(scene: &Scene, specs: &[MapSpec], jobs: &[Job]) -> Self {
        let o = &scene.orbit;
        let samples = (0..o.sample_count())
            .map(|k| {
                let (azimuth_deg, elevation_deg) = o.sample_angles(k);
                SampleJson {
                    index: k,
                    azimuth_deg,
                    elevation_deg,
                    eye: o.eye(azimuth_deg, elevation_deg).to_array(),
                    files: specs.iter().map(|s| (s.name(), file_name(s, k))).collect(),
                }
            })
            .collect();
        Sidecar {
            format: "pem-engine maps",
            version: SIDECAR_VERSION,
            scene: scene.name.clone(),
            scene_file: scene.source.display().to_string(),
            vk_format: "VK_FORMAT_R32G32B32A32_SFLOAT",
            face_order: ["+X", "-X", "+Y", "-Y", "+Z", "-Z"],
            orbit: OrbitJson {
                center: o.center.to_array(),
                radius: o.radius,
                height: o.height,
                start_deg: o.start_deg,
                step_deg: o.step_deg,
                azimuth_lines: o.samples,
                azimuths_deg: o.azimuths.clone(),
                rings: o.rings.max(1),
                ring_step_deg: o.ring_step_deg,
                ring_elevations_deg: o.elevations.clone(),
                ring_line_every: (!o.is_tensor()).then_some(o.ring_line_every),
            },
            maps: specs.iter().map(|s| map_json(s, jobs)).collect(),
            samples,
        }
    }
}

fn map_json(spec: &MapSpec, jobs: &[Job]) -> MapJson {
    let layout = spec.layout();
    let job = jobs
        .iter()
        .find(|j| j.object.name == spec.object && j.layer == spec.layer);
    let em = job.and_then(|j| {
        Some(em_json(
            j.geometry?,
            j.origin.to_array(),
            j.object.lod_bias(),
        ))
    });
    MapJson {
        name: spec.name(),
        object: spec.object.clone(),
        layer: match spec.layer {
            MapLayer::Distant => "distant",
            MapLayer::Local => "local",
            MapLayer::Sphere => "sphere",
            MapLayer::Ptm => "ptm",
        },
        kind: if layout.faces() == 6 { "cube" } else { "2d" },
        size: layout.level_size(0).0,
        levels: layout.levels(),
        inferred_channels: spec.layer.channels(),
        alpha: if spec.layer == MapLayer::Local {
            "premultiplied"
        } else {
            "opaque"
        },
        em,
        atlas: (spec.layer == MapLayer::Ptm).then(|| super::atlas_file_name(&spec.object)),
    }
}

fn em_json(geometry: EmGeometry, lookup_origin: [f32; 3], lod_bias: f32) -> EmJson {
    let mut em = EmJson {
        geometry: "sphere_at_infinity",
        center: None,
        box_min: None,
        box_max: None,
        radii: None,
        lookup_origin,
        lod_bias,
    };
    match geometry {
        EmGeometry::SphereAtInfinity => {}
        EmGeometry::Box { min, max } => {
            em.geometry = "box";
            em.center = Some(((min + max) * 0.5).to_array());
            em.box_min = Some(min.to_array());
            em.box_max = Some(max.to_array());
        }
        EmGeometry::Ellipsoid { center, radii } => {
            em.geometry = "ellipsoid";
            em.center = Some(center.to_array());
            em.radii = Some(radii.to_array());
        }
    }
    em
}
