//! The scene: camera, orbit, room, lights, materials, baked textures and world-space
//! meshes, loaded from a human-editable TOML file (`assets/scenes/<name>.toml`).

pub mod camera;
pub mod error;
mod file;
pub mod light;
mod load;
pub mod material;
pub mod mesh;
pub mod obj;
pub mod paths;
pub mod room;
pub mod texture;

#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use glam::Vec3;

pub use crate::fresnel::schlick_fresnel;
pub use camera::{Camera, Orbit};
pub use error::SceneError;
pub use light::AreaLight;
pub use material::{EmLayer, EmSettings, Material};
pub use mesh::Mesh;
pub use paths::{assets_dir, cache_dir, workspace_dir};
pub use texture::{Pattern, Texture};

/// A loaded, validated scene. Room surfaces ("floor", "walls", "ceiling") and lights are
/// objects too, so a rasteriser draws everything from `objects` alone.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The scene file this was loaded from.
    pub source: PathBuf,
    pub camera: Camera,
    pub orbit: Orbit,
    pub lights: Vec<AreaLight>,
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
    /// Already in world space.
    pub mesh: Mesh,
    pub material: usize,
    /// Set for objects that get parameterized environment maps.
    pub em: Option<EmSettings>,
}

impl Scene {
    /// `name_or_path`: a scene name (file `assets/scenes/<name>.toml`) or a path to a
    /// `.toml` file. Generated meshes are cached in [`cache_dir`].
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        Scene::load_with_cache(name_or_path, &cache_dir())
    }

    /// As [`Scene::load`], with generated meshes cached in `cache_dir`.
    pub fn load_with_cache(name_or_path: &str, cache_dir: &Path) -> Result<Scene, SceneError> {
        let path = scene_path(name_or_path);
        let text = std::fs::read_to_string(&path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => SceneError::NoScene {
                available: available_scenes(&path),
                path: path.clone(),
            },
            _ => SceneError::io(&path, e),
        })?;
        Scene::from_toml(&text, &path, cache_dir)
    }

    /// Parses scene text; `path` is used for error messages and relative mesh paths.
    pub fn from_toml(text: &str, path: &Path, cache_dir: &Path) -> Result<Scene, SceneError> {
        let file: file::SceneFile = toml::from_str(text).map_err(|e| SceneError::Toml {
            path: path.to_owned(),
            cause: Box::new(e),
        })?;
        load::Loader { path, cache_dir }.build(file)
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

/// Stems of the `.toml` files beside `path`, for "did you mean" messages.
fn available_scenes(path: &Path) -> String {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    if names.is_empty() {
        "none".to_owned()
    } else {
        names.join(", ")
    }
}

/// A bare name (no separator, no `.toml`) means `assets/scenes/<name>.toml`.
fn scene_path(name_or_path: &str) -> PathBuf {
    let p = Path::new(name_or_path);
    if p.extension().is_some_and(|e| e == "toml") || p.components().count() > 1 {
        p.to_owned()
    } else {
        assets_dir()
            .join("scenes")
            .join(format!("{name_or_path}.toml"))
    }
}
