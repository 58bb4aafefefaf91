//! The teapot as an OBJ file in the cache: the engine consumes every mesh through OBJ.

use std::path::{Path, PathBuf};

use super::{TeapotPart, tessellate};
use crate::scene::error::SceneError;
use crate::scene::obj::write_obj;

/// Bump when the tessellation output changes, so stale cache files are not reused.
const GENERATOR_VERSION: u32 = 1;

/// Cache file name, keyed by everything that determines its contents.
pub fn obj_file_name(segments: u32, part: TeapotPart) -> String {
    format!(
        "newell_teapot_{}_n{segments}_v{GENERATOR_VERSION}.obj",
        part.name()
    )
}

/// Path of the teapot OBJ in `cache_dir`, tessellating and writing it first if missing.
/// The write is atomic (temp file + rename), so a concurrent reader never sees half a file.
pub fn cached_obj(
    segments: u32,
    part: TeapotPart,
    cache_dir: &Path,
) -> Result<PathBuf, SceneError> {
    let path = cache_dir.join(obj_file_name(segments, part));
    if path.is_file() {
        return Ok(path);
    }
    let t = tessellate(segments, part)?;
    let header = format!(
        "Newell's Utah teapot ({} patches), {segments} segments per patch edge, y up, original units",
        part.name()
    );
    write_obj(&path, &t.mesh, &header)?;
    Ok(path)
}
