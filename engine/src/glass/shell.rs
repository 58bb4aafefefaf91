//! Compiling the room shell's map (`inference::glass::shell_map`): traced
//! once per scene and size, cached beside the other compiled files as f16
//! RGBA texels in upload order with a content-key record.

use anyhow::{Context, Result};
use glam::Vec3;
use half::f16;
use inference::key::Freshness;
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer, cache};
use std::path::{Path, PathBuf};

/// Samples per texel of the traced shell map.
pub const SHELL_SPP: u32 = 8;
/// Bumped when what the map holds changes.
const SHELL_VERSION: u64 = 1;

/// Where the room shell map of `scene` is cached under `out`.
pub fn shell_path(out: &Path) -> PathBuf {
    out.join("glass").join("room_shell.bin")
}

/// How a shell map of `size`² per face is traced.
pub fn shell_settings(size: u32) -> TraceSettings {
    TraceSettings {
        width: size,
        height: 6 * size,
        spp: SHELL_SPP,
        ..TraceSettings::default()
    }
}

/// What the cached shell map of `scene`'s lens `skip` at `origin` depends on.
pub fn shell_key(scene: &Scene, skip: u32, origin: Vec3, size: u32) -> inference::key::Key {
    cache::image_key(&cache::scene_key(scene), origin, &shell_settings(size))
        .with("glass shell", SHELL_VERSION)
        .with("lens", u64::from(skip))
}

/// The f16 RGBA bytes (every level, level-major, face, rows) of the room
/// shell map at `origin`, `size`² per face, the object `skip` (the lens)
/// transparent: read from `out` when fresh, else traced and written.
pub fn room_shell_bytes(
    scene: &Scene,
    out: &Path,
    skip: u32,
    origin: Vec3,
    size: u32,
) -> Result<Vec<u8>> {
    let key = shell_key(scene, skip, origin, size);
    cached_map(&shell_path(out), &key, size, "the room shell map", || {
        let tracer = Tracer::new(scene)?;
        let settings = shell_settings(size);
        let rgb =
            inference::glass::shell_map::trace_shell_map(&tracer, skip, origin, size, &settings);
        Ok(rgb.into_iter().map(|[r, g, b]| [r, g, b, 1.0]).collect())
    })
}

/// A traced cube map's f16 RGBA bytes (every level, level-major, face,
/// rows), cached at `file` under `key`: read when fresh, else `trace`d
/// (level 0, `size`² × 6 texels), box-filtered down its MIP chain and
/// written with the key (never over a file the engine did not write).
pub fn cached_map(
    file: &Path,
    key: &inference::key::Key,
    size: u32,
    what: &str,
    trace: impl FnOnce() -> Result<Vec<[f32; 4]>>,
) -> Result<Vec<u8>> {
    if inference::key::freshness(file, key) == Freshness::Fresh {
        match inference::key::read_verified(file) {
            Ok(bytes) => return Ok(bytes),
            Err(why) => eprintln!("{why}: tracing it again"),
        }
    }
    crate::util::files::check_overwrite_keyed(file)?;
    let start = std::time::Instant::now();
    let levels = inference::glass::shell_map::mip_chain(trace()?, size);
    let halves: Vec<f16> = levels
        .iter()
        .flatten()
        .flat_map(|t| t.map(f16::from_f32))
        .collect();
    let bytes: Vec<u8> = bytemuck::cast_slice(&halves).to_vec();
    let dir = file.parent().unwrap_or(file);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    inference::files::write_bytes(file, &bytes)?;
    inference::key::write_record(file, key)?;
    eprintln!(
        "traced {what} ({size}² × 6, {SHELL_SPP} spp) in {:.1} s: {}",
        start.elapsed().as_secs_f64(),
        file.display()
    );
    Ok(bytes)
}
