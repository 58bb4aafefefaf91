//! The one error type for scene, mesh, OBJ and glTF loading.

use std::path::PathBuf;

use super::Origin;

/// Everything a user, a scene file or a mesh file can get wrong. Every variant names the file
/// (a built-in scene by its name: [`Origin`]).
/// Each message is complete on one line, inner errors included, so they are not also
/// exposed as `source()` (anyhow's `{:#}` would print them twice).
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// The scene file does not exist; `available` lists the scenes beside where it was sought.
    #[error("{}: no such scene file (available: {available})", path.display())]
    NoScene { path: PathBuf, available: String },
    /// A folder was given where a scene file was expected.
    #[error("{}: a folder, expected a .toml scene file (scenes in it: {available})", path.display())]
    Folder { path: PathBuf, available: String },
    /// TOML syntax or type error; `toml`'s message carries line and column.
    #[error("{scene}: {cause}")]
    Toml {
        scene: Origin,
        cause: Box<toml::de::Error>,
    },
    /// A value that parsed but makes no sense; `field` is a path like `objects[0].material`.
    #[error("{scene}: {field}: {message}")]
    Invalid {
        scene: Origin,
        field: String,
        message: String,
    },
    /// A bad OBJ file; `location` is e.g. `line 12` or `face 7 of object "body"`.
    #[error("{}: {location}: {message}", path.display())]
    Obj {
        path: PathBuf,
        location: String,
        message: String,
    },
    /// A bad glTF file; `location` is e.g. `buffer 0` or `mesh 2 "body", primitive 0`.
    #[error("{}: {location}: {message}", path.display())]
    Gltf {
        path: PathBuf,
        location: String,
        message: String,
    },
    /// An error inside a file the scene refers to, e.g. a mesh.
    #[error("{scene}: {field}: {cause}")]
    Nested {
        scene: Origin,
        field: String,
        cause: Box<SceneError>,
    },
    #[error("orbit sample {sample} out of range 0..{samples}")]
    OrbitSampleOutOfRange { sample: u32, samples: u32 },
    #[error("tessellation segments must be in 1..={max}, got {segments}")]
    Segments { segments: u32, max: u32 },
}

impl SceneError {
    pub(crate) fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        SceneError::Io {
            path: path.into(),
            cause,
        }
    }

    pub(crate) fn obj(
        path: impl Into<PathBuf>,
        location: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Obj {
            path: path.into(),
            location: location.into(),
            message: message.into(),
        }
    }

    pub(crate) fn gltf(
        path: impl Into<PathBuf>,
        location: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Gltf {
            path: path.into(),
            location: location.into(),
            message: message.into(),
        }
    }
}
