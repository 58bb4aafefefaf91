//! The scene: camera, orbit, room, lights, materials, baked textures and world-space
//! meshes, loaded from a human-editable TOML file (`assets/scenes/<name>.toml`).

pub mod camera;
pub mod error;
mod file;
pub mod glass;
pub mod gltf;
pub mod grid;
pub mod light;
mod load;
mod local_group;
pub mod material;
pub mod mesh;
pub mod obj;
mod origin;
pub mod pattern_filter;
pub mod placed;
pub mod ring_lines;
pub mod room;
pub mod shipped;
pub mod texture;

#[cfg(test)]
mod em_tests;
#[cfg(test)]
mod glass_tests;
#[cfg(test)]
mod object_tests;
#[cfg(test)]
mod orbit_tests;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use glam::Vec3;

pub use crate::fresnel::schlick_fresnel;
pub use camera::{Camera, Orbit};
pub use error::SceneError;
pub use glass::GlassSettings;
pub use grid::{SampleBlend, ViewBlend, ViewGrid};
pub use light::{AreaLight, DirectionalLight, PointLight};
pub use material::{EM_RESOLUTIONS, EmLayer, EmSettings, LOD_BIASES, Material};
pub use mesh::Mesh;
pub use origin::Origin;
pub use shipped::{SHIPPED, shipped};
pub use texture::{Pattern, PatternSource, Texture};

/// A loaded, validated scene. Room surfaces ("floor", "walls", "ceiling") and lights are
/// objects too, so a rasteriser draws everything from `objects` alone.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The scene file this was loaded from (a built-in's: the repository
    /// path its text comes from, `assets/scenes/<name>.toml`); relative mesh
    /// paths are relative to it.
    pub source: PathBuf,
    /// What messages call it: `built-in scene 'teapot'` or the file's path.
    pub origin: Origin,
    pub camera: Camera,
    pub orbit: Orbit,
    pub lights: Vec<AreaLight>,
    /// Optional parallel lights (`[[directional_lights]]`); none in the shipped scenes.
    pub directional_lights: Vec<DirectionalLight>,
    /// Optional point lights (`[[point_lights]]`); none in the shipped scenes.
    pub point_lights: Vec<PointLight>,
    /// Declared materials sorted by name, then one emissive material per light.
    pub materials: Vec<Material>,
    /// Name of each entry of `materials` (a light's material carries the light's name).
    pub material_names: Vec<String>,
    pub objects: Vec<Object>,
    pub textures: Vec<Texture>,
}

/// A named mesh with a material (index into `Scene::materials`).
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    /// Already in world space: what the engine draws, solves and plays.
    pub mesh: Mesh,
    /// The surface the tracer (the gold standard) sees instead, when the
    /// scene gives one (`mesh.trace_segments`): finer than what playback
    /// needs to draw (README "Coarser playback tessellation").
    pub trace_mesh: Option<Mesh>,
    pub material: usize,
    /// Set for objects that get parameterized environment maps.
    pub em: Option<EmSettings>,
    /// Set for glass objects rendered by hybrid rendering (`[objects.glass]`).
    pub glass: Option<GlassSettings>,
}

impl Object {
    /// The mesh the tracer intersects: [`Object::trace_mesh`] where the
    /// scene gives one, else the one the engine draws.
    pub fn traced_mesh(&self) -> &Mesh {
        self.trace_mesh.as_ref().unwrap_or(&self.mesh)
    }

    /// The LOD bias of the object's EM lookups (`[objects.em] lod_bias`;
    /// 0, the hardware's own level of detail, without EMs).
    pub fn lod_bias(&self) -> f32 {
        self.em.as_ref().map_or(0.0, |em| em.lod_bias)
    }

    /// The weight of the bounds on the object's local layer
    /// (`[objects.em] local_bound`; 0, off, without EMs).
    pub fn local_bound(&self) -> f32 {
        self.em.as_ref().map_or(0.0, |em| em.local_bound)
    }

    /// Whether the object's solves weight rows as the display shows their
    /// errors (`[objects.em] display_weight`; off without EMs).
    pub fn display_weight(&self) -> bool {
        self.em.as_ref().is_some_and(|em| em.display_weight)
    }

    /// The weight of neighbouring samples' views in the object's EM solves
    /// (`[objects.em] neighbour_weight`; 0 without EMs).
    pub fn neighbour_weight(&self) -> f32 {
        self.em.as_ref().map_or(0.0, |em| em.neighbour_weight)
    }

    /// How far either side of a sample the views stacked into its EM
    /// solves lie (`[objects.em] neighbour_deg`); None stacks the
    /// neighbouring samples' views.
    pub fn neighbour_deg(&self) -> Option<f32> {
        self.em.as_ref().and_then(|em| em.neighbour_deg)
    }

    /// The elevations above each sample of the further views stacked into
    /// its EM solves (`[objects.em] neighbour_above_deg`); empty for none.
    pub fn neighbour_above_deg(&self) -> &[f32] {
        self.em.as_ref().map_or(&[], |em| &em.neighbour_above_deg)
    }

    /// The azimuth spacing of shared views above
    /// (`[objects.em] neighbour_above_spacing_deg`); None puts them at
    /// every sample.
    pub fn neighbour_above_spacing_deg(&self) -> Option<f32> {
        self.em
            .as_ref()
            .and_then(|em| em.neighbour_above_spacing_deg)
    }

    /// The weight the scene gives the views above in the object's EM
    /// solves (`[objects.em] neighbour_above_weight`); None when unset,
    /// where they take `neighbour_weight`.
    pub fn neighbour_above_weight(&self) -> Option<f32> {
        self.em.as_ref().and_then(|em| em.neighbour_above_weight)
    }
}

impl Scene {
    /// `name_or_path`: the name of a shipped scene (built into the binary,
    /// [`SHIPPED`]) or a path to a `.toml` file. Relative mesh paths are
    /// relative to the scene file.
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        let (text, source, origin) = Scene::read(name_or_path)?;
        Scene::parse(&text, &source, origin)
    }

    /// The text of a built-in scene or a scene file, and the path it is
    /// known by (built-ins: `assets/scenes/<name>.toml`).
    pub fn text(name_or_path: &str) -> Result<(String, PathBuf), SceneError> {
        Scene::read(name_or_path).map(|(text, source, _)| (text, source))
    }

    /// [`Scene::text`], and what messages call the scene.
    fn read(name_or_path: &str) -> Result<(String, PathBuf, Origin), SceneError> {
        let p = Path::new(name_or_path);
        let is_path = p.extension().is_some_and(|e| e == "toml") || p.components().count() > 1;
        if p.is_dir() && (is_path || shipped(name_or_path).is_none()) {
            return Err(SceneError::Folder {
                path: p.to_owned(),
                available: available_scenes(&p.join("scene.toml")),
            });
        }
        if !is_path {
            let Some(text) = shipped(name_or_path) else {
                return Err(SceneError::NoScene {
                    path: p.to_owned(),
                    available: format!(
                        "built-in scenes: {}; or give a path to a .toml file",
                        shipped::shipped_names()
                    ),
                });
            };
            let source = Path::new("assets/scenes").join(format!("{name_or_path}.toml"));
            let origin = Origin::BuiltIn(name_or_path.to_owned());
            return Ok((text.to_owned(), source, origin));
        }
        let text = std::fs::read_to_string(p).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => SceneError::NoScene {
                available: available_scenes(p),
                path: p.to_owned(),
            },
            _ => SceneError::io(p, e),
        })?;
        Ok((text, p.to_owned(), Origin::File(p.to_owned())))
    }

    /// Parses scene text; `path` is used for error messages and relative mesh paths.
    pub fn from_toml(text: &str, path: &Path) -> Result<Scene, SceneError> {
        Scene::parse(text, path, Origin::File(path.to_owned()))
    }

    /// Parses scene text read from `origin`; `path` (its file, or a
    /// built-in's repository path) anchors relative mesh paths.
    fn parse(text: &str, path: &Path, origin: Origin) -> Result<Scene, SceneError> {
        let file: file::SceneFile = toml::from_str(text).map_err(|e| SceneError::Toml {
            scene: origin.clone(),
            cause: Box::new(e),
        })?;
        load::Loader {
            path,
            origin: &origin,
        }
        .build(file)
    }

    /// How to name this scene on the command line: the built-in scene's
    /// name, or the path of the file it was loaded from.
    pub fn arg(&self) -> String {
        match &self.origin {
            Origin::BuiltIn(name) => name.clone(),
            Origin::File(path) => path.display().to_string(),
        }
    }

    /// Bounds of all objects, room included: `(min, max)`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.objects
            .iter()
            .filter(|o| !o.mesh.positions.is_empty())
            .map(|o| o.mesh.bounds())
            .fold(None, |acc: Option<(Vec3, Vec3)>, (lo, hi)| {
                Some(acc.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
            })
            .unwrap_or((Vec3::ZERO, Vec3::ZERO))
    }

    pub fn object(&self, name: &str) -> Option<&Object> {
        self.objects.iter().find(|o| o.name == name)
    }

    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.material_names.iter().position(|n| n == name)
    }
}

/// The folder a file path lies in: "." for a bare file name (whose
/// `parent()` is empty, which `read_dir` refuses).
fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Stems of the `.toml` files beside `path` and the built-in scenes, for
/// "did you mean" messages.
fn available_scenes(path: &Path) -> String {
    let dir = folder_of(path);
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    let beside = if names.is_empty() {
        "none".to_owned()
    } else {
        names.join(", ")
    };
    format!("{beside}; built-in scenes: {}", shipped::shipped_names())
}
