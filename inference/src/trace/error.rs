//! The tracer's error type: every variant names the file or field at fault.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// A scene the tracer cannot render; `field` is a path like `lights[0]`.
    #[error("{scene}: {field}: {message}")]
    Scene {
        scene: crate::scene::Origin,
        field: String,
        message: String,
    },
    /// Settings out of range; `field` names the setting (`spp`, `size`, ...).
    #[error("trace settings: {field}: {message}")]
    Settings {
        field: &'static str,
        message: String,
    },
    #[error(transparent)]
    Load(#[from] crate::scene::SceneError),
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: EXR: {cause}", path.display())]
    Exr {
        path: PathBuf,
        cause: exr::error::Error,
    },
    /// An EXR whose header declares more than any the engine writes.
    #[error("{}: EXR header: {declared}", path.display())]
    ExrSize { path: PathBuf, declared: String },
    #[error("{}: writing PNG: {cause}", path.display())]
    Png {
        path: PathBuf,
        cause: image::ImageError,
    },
    #[error("cannot start {threads} tracer threads: {cause}")]
    Threads {
        threads: usize,
        cause: rayon::ThreadPoolBuildError,
    },
}

impl TraceError {
    pub fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        TraceError::Io {
            path: path.into(),
            cause,
        }
    }
}
