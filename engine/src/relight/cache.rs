//! The traced light grid, projected, cached under `<out>/relight/`: one file
//! of SH maps (k = 25; every smaller k is a prefix) and the position panorama,
//! with a key record beside it (`inference::key`), rebuilt when the scene,
//! the panorama settings or the grid change, or when it fails to read.
//! The grid's raw panoramas are not kept (25 planes instead of 128), and the
//! file is raw little-endian floats, not the codec's container.

use anyhow::{Context, Result, bail};
use glam::Vec3;
use inference::key::{Fnv, Freshness, Key};
use inference::relight::sh::MAX_K;
use inference::relight::{
    LightGrid, MovingLight, Panorama, PanoramaSettings, RelightScene, ShMaps,
};
use inference::scene::Scene;
use std::hash::Hasher;
use std::path::{Path, PathBuf};

use crate::util::files;

/// Changes whenever the traced or projected numbers would.
pub const RELIGHT_VERSION: u32 = 1;
const MAGIC: &[u8; 8] = b"PEMSH001";

/// Panorama texels at most: the SH maps hold [`BYTES_PER_TEXEL`] per
/// texel (1.3 GB here), so an 8192² panorama (20 GB) is refused up front
/// rather than failing to allocate.
const MAX_TEXELS: u64 = 4096 * 1024;
/// The maps' bytes per texel: [`MAX_K`] coefficients × RGB × f32.
const BYTES_PER_TEXEL: u64 = MAX_K as u64 * 3 * 4;

/// What the grid is traced and projected with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSettings {
    pub trace: PanoramaSettings,
    /// Gauss–Legendre rings × azimuths.
    pub grid: (u32, u32),
}

impl GridSettings {
    /// Checked settings: a `width × height` panorama (both 1 to 8192, at
    /// most [`MAX_TEXELS`] texels), a
    /// grid up to 64 × 128, 1 to 1024 samples per texel, at most 8 bounces;
    /// `what` names the flags in the message.
    pub fn new(
        (width, height): (u32, u32),
        (rings, azimuths): (u32, u32),
        spp: u32,
        bounces: u32,
        seed: u64,
        what: &str,
    ) -> Result<Self> {
        let size_ok = (1..=8192).contains(&width) && (1..=8192).contains(&height);
        if !size_ok
            || !(1..=64).contains(&rings)
            || !(1..=128).contains(&azimuths)
            || !(1..=1024).contains(&spp)
            || bounces > 8
        {
            bail!(
                "{what}: size {width}x{height}, grid {rings}x{azimuths}, {spp} spp, {bounces} \
                 bounces: expected a size up to 8192 a side, a grid up to 64x128, 1 to 1024 \
                 samples and at most 8 bounces"
            );
        }
        let texels = u64::from(width) * u64::from(height);
        if texels > MAX_TEXELS {
            let gb = (texels * BYTES_PER_TEXEL) as f64 / 1e9;
            bail!(
                "{what}: size {width}x{height}: its SH maps would take {gb:.1} GB ({MAX_K} coefficients \
                 × RGB × f32 per texel); expected at most {MAX_TEXELS} texels (e.g. 4096x1024)"
            );
        }
        Ok(Self {
            trace: PanoramaSettings {
                panorama: Panorama { width, height },
                spp,
                seed,
                bounces,
            },
            grid: (rings, azimuths),
        })
    }
}

/// SH maps (k = 25) and the world position of each texel's first hit.
pub struct Relightable {
    pub maps: ShMaps,
    pub positions: Vec<Vec3>,
    /// Read from the cache (no tracing).
    pub cached: bool,
    pub trace_s: f64,
    pub path: PathBuf,
    /// The key the maps are cached under (what made them).
    pub key: Key,
}

pub fn key(scene: &Scene, settings: &GridSettings) -> Key {
    let mut h = Fnv::default();
    let t = &settings.trace;
    h.write_u32(t.panorama.width);
    h.write_u32(t.panorama.height);
    h.write_u32(t.spp);
    h.write_u64(t.seed);
    h.write_u32(t.bounces);
    h.write_u32(settings.grid.0);
    h.write_u32(settings.grid.1);
    inference::trace::cache::scene_key(scene)
        .with("relight version", u64::from(RELIGHT_VERSION))
        .with(
            "tracer version",
            u64::from(inference::trace::cache::TRACER_VERSION),
        )
        .with("relight settings", h.finish())
}

/// The cached maps for `settings`, or traced (with a progress bar when
/// `progress`) and cached under `out/relight/`.
pub fn relightable(
    scene: &Scene,
    settings: &GridSettings,
    out: &Path,
    progress: bool,
) -> Result<Relightable> {
    let dir = out.join("relight");
    files::claim_dir(&dir)?;
    let p = settings.trace.panorama;
    let (r, a) = settings.grid;
    let path = dir.join(format!("sh_{}x{}_grid{r}x{a}.bin", p.width, p.height));
    let key = key(scene, settings);
    if matches!(inference::key::freshness(&path, &key), Freshness::Fresh) {
        match inference::key::read_verified(&path)
            .map_err(anyhow::Error::msg)
            .and_then(|b| decode(&b, p))
        {
            Ok((maps, positions)) => {
                return Ok(Relightable {
                    maps,
                    positions,
                    cached: true,
                    trace_s: 0.0,
                    path,
                    key,
                });
            }
            Err(e) => eprintln!("{}: rebuilding ({e:#})", path.display()),
        }
    }
    files::check_overwrite_keyed(&path)?;
    let start = std::time::Instant::now();
    let (maps, positions) = trace_grid(scene, settings, progress);
    files::write(&path, &encode(&maps, &positions))?;
    inference::key::write_record(&path, &key)?;
    Ok(Relightable {
        maps,
        positions,
        cached: false,
        trace_s: start.elapsed().as_secs_f64(),
        path,
        key,
    })
}

/// Traces the room under every grid direction and projects as it goes.
pub fn trace_grid(scene: &Scene, settings: &GridSettings, progress: bool) -> (ShMaps, Vec<Vec3>) {
    let grid = LightGrid::new(settings.grid.0, settings.grid.1);
    let mut relit = RelightScene::new(scene);
    let bar = if progress {
        indicatif::ProgressBar::new(grid.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "relight grid [{bar:30}] {pos}/{len} light directions {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut maps = ShMaps::zeros(settings.trace.panorama, MAX_K);
    for (d, w) in grid.directions.iter().zip(&grid.weights) {
        let f = relit.trace(MovingLight::Directional(*d), &settings.trace);
        maps.accumulate(*d, *w, &f);
        bar.inc(1);
    }
    bar.finish_and_clear();
    (maps, relit.positions(settings.trace.panorama))
}

fn encode(maps: &ShMaps, positions: &[Vec3]) -> Vec<u8> {
    let mut b = MAGIC.to_vec();
    for v in [maps.panorama.width, maps.panorama.height, maps.k as u32] {
        b.extend(v.to_le_bytes());
    }
    b.extend(maps.coeffs.iter().flat_map(|x| x.to_le_bytes()));
    b.extend(
        positions
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(f32::to_le_bytes),
    );
    b
}

fn decode(bytes: &[u8], expected: Panorama) -> Result<(ShMaps, Vec<Vec3>)> {
    let word = |i: usize| -> Result<u32> {
        let s = bytes
            .get(8 + 4 * i..12 + 4 * i)
            .context("truncated header")?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    };
    if bytes.get(..8) != Some(&MAGIC[..]) {
        bail!("not a relight map file (expected magic {MAGIC:?})");
    }
    let (w, h, k) = (word(0)?, word(1)?, word(2)? as usize);
    if (w, h) != (expected.width, expected.height) || k != MAX_K {
        bail!(
            "holds {w}x{h}, k = {k}; expected {}x{}, k = {MAX_K}",
            expected.width,
            expected.height
        );
    }
    let texels = expected.texels();
    let floats: Vec<f32> = bytes[20..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if floats.len() != texels * (3 * k + 3) {
        bail!("{} floats, expected {}", floats.len(), texels * (3 * k + 3));
    }
    let (coeffs, pos) = floats.split_at(texels * 3 * k);
    let positions = pos.chunks_exact(3).map(Vec3::from_slice).collect();
    Ok((
        ShMaps {
            panorama: expected,
            k,
            coeffs: coeffs.to_vec(),
        },
        positions,
    ))
}

#[cfg(test)]
mod tests {
    use super::GridSettings;

    #[test]
    fn panoramas_too_large_for_memory_are_refused_with_their_size() {
        let ok = GridSettings::new((4096, 1024), (8, 16), 2, 1, 0, "--size");
        assert!(ok.is_ok(), "{:?}", ok.err());
        let e = GridSettings::new((8192, 8192), (8, 16), 2, 1, 0, "--size")
            .expect_err("20 GB of maps")
            .to_string();
        assert!(
            e.contains("--size") && e.contains("20.1 GB") && e.contains("4194304"),
            "{e}"
        );
    }
}
