//! Where assets and generated files live.

use std::path::PathBuf;

/// The workspace root (parent of this crate's manifest directory).
pub fn workspace_dir() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(PathBuf::from).unwrap_or(manifest)
}

/// `$ENGINE_ASSETS` if set, else `<workspace>/assets`.
pub fn assets_dir() -> PathBuf {
    std::env::var_os("ENGINE_ASSETS")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_dir().join("assets"))
}

/// `$ENGINE_CACHE` if set, else `<workspace>/out/cache`: generated meshes and the like,
/// safe to delete.
pub fn cache_dir() -> PathBuf {
    std::env::var_os("ENGINE_CACHE")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_dir().join("out").join("cache"))
}
