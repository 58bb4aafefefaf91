//! Encoding: every sample's inferred maps into one container per scene,
//! at a size that holds the quality. A container that would decode far
//! below [`MIN_TEXTURE_PSNR_DB`] (maps too small for the ratio asked) is
//! encoded again with more bytes, never played black.

use crate::maps::{MapSet, MapSpec, map_path, sample_dir};
use crate::util::files::check_overwrite_keyed;
use anyhow::{Context, Result, bail};
use codec::quality::PsnrAccum;
use codec::{EncodeInput, EncodeOptions, LeafLayout, ParamGrid, ParamTexture, Target, TextureId};
use inference::infer::maps::parse_map;
use inference::key::Key;
use inference::scene::Scene;
use std::path::Path;

/// The lowest texture PSNR (the codec's definition, `codec::quality`) a
/// container may decode to; the teapot's maps reach ~50 dB at 384:1.
pub const MIN_TEXTURE_PSNR_DB: f64 = 35.0;
/// The ratio asked for when none is given (the thesis's 384:1).
pub const DEFAULT_RATIO: f64 = 384.0;
/// f16's largest finite value: what playback's textures can hold.
const F16_MAX: f32 = 65504.0;
/// What a compression ratio must be (against 32-bit floats), as every
/// refusal of one words it.
pub const RATIO_EXPECTED: &str = "a compression ratio above 1 and at most 100,000 (e.g. 384)";
/// `relight`'s limit before the commands shared one check: a far larger
/// ratio is no useful aim, and refused up front it cannot fail only after
/// the tracing, when the maps are encoded.
const MAX_RATIO: f64 = 100_000.0;

/// Refuses a ratio the codec cannot aim at ([`RATIO_EXPECTED`]): the one
/// check of `--ratio` for `engine encode`, `engine relight` and
/// `engine codec-report --curve-ratios`, made before any work.
pub fn check_ratio(ratio: f64) -> Result<()> {
    if !(ratio > 1.0 && ratio <= MAX_RATIO) {
        bail!("--ratio {ratio}: expected {RATIO_EXPECTED}");
    }
    Ok(())
}

/// The codec's parameter grid of `orbit`'s viewpoint samples: its azimuth
/// lines × elevation rings as a 2D grid (2D 8×8 parameter blocks, thesis
/// ch. 4) when it has rings, else the 1D orbit (and the rings one after
/// another when the upper ones skip lines: not a grid). Sample `k` is the
/// grid's linear index `k`.
pub fn orbit_grid(orbit: &inference::scene::Orbit) -> ParamGrid {
    if orbit.rings > 1 && orbit.is_tensor() {
        ParamGrid::two_d(orbit.samples, orbit.rings)
    } else {
        ParamGrid::one_d(orbit.sample_count())
    }
}

/// A map that could not be used for encoding: which one, and why.
#[derive(Debug, thiserror::Error)]
#[error("{why}")]
pub struct BadMap {
    pub sample: u32,
    pub spec: usize,
    pub path: std::path::PathBuf,
    /// The whole message, naming the map's file (as the key records' and
    /// the maps' readers do).
    pub why: String,
}

/// A command that reads every inferred map: what it says when the scene
/// has none, or one is missing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapsFor {
    /// `engine encode` and the compile: the maps are compressed.
    Encode,
    /// `engine codec-report`: the container is measured against them.
    Report,
    /// `engine export --ktx2`: the maps are written for other engines.
    Export,
}

impl MapsFor {
    /// Why a scene without parameterized maps is refused.
    fn nothing(self) -> &'static str {
        match self {
            MapsFor::Encode => "nothing to encode",
            MapsFor::Report => "this scene has no parameterized maps to report on",
            MapsFor::Export => "no maps to export",
        }
    }

    /// What the command does with the maps.
    fn needs(self) -> &'static str {
        match self {
            MapsFor::Encode => "encode compresses the inferred maps",
            MapsFor::Report => {
                "codec-report compares the container against the uncompressed inferred maps it was encoded from"
            }
            MapsFor::Export => {
                "export writes the inferred maps as KTX2 files (the main job playing a shipped compiled scene infers none)"
            }
        }
    }
}

/// The scene's maps of `set`, refused when it has none.
fn specs_for(scene: &Scene, set: MapSet, purpose: MapsFor) -> Result<Vec<MapSpec>> {
    let specs = set.specs(scene);
    if specs.is_empty() {
        bail!(
            "{}: no reflective object has [objects.em] settings: {}",
            scene.origin,
            purpose.nothing()
        );
    }
    Ok(specs)
}

/// Every sample's maps of `set`: their key records in `infer_dir`, in
/// [`load_input`]'s order. A map missing, or without its record, is
/// refused naming it, its sample, the folder (and whether it exists), what
/// `purpose` needs the maps for and how to make them.
pub fn map_keys(
    scene: &Scene,
    set: MapSet,
    infer_dir: &Path,
    purpose: MapsFor,
) -> Result<Vec<Key>> {
    let specs = specs_for(scene, set, purpose)?;
    let mut keys = Vec::new();
    for k in 0..scene.orbit.sample_count() {
        for spec in &specs {
            let path = map_path(infer_dir, k, &spec.object, spec.layer);
            let record = inference::key::read_record(&path).filter(|_| path.is_file());
            let Some(record) = record else {
                let folder = if infer_dir.is_dir() {
                    ""
                } else {
                    "; no such folder"
                };
                bail!(
                    "{}: missing or without its key record: {}, and looks for them in {}; make them with `engine infer --scene {} --all --out {}`, or point --infer-dir at them (sample {k}'s {}{folder})",
                    path.display(),
                    purpose.needs(),
                    infer_dir.display(),
                    scene.arg(),
                    infer_dir.display(),
                    spec.name()
                );
            };
            keys.push(record.key);
        }
    }
    Ok(keys)
}

/// Reads every sample's maps of `set` into the codec's input
/// (sample-major; each sample MIP-major, then face, rows, texels, channels
/// interleaved) for `purpose`. A map that is missing, damaged (its key record's checksum)
/// or holds values playback cannot (beyond f16) is a [`BadMap`] naming it.
pub fn load_input(
    scene: &Scene,
    set: MapSet,
    infer_dir: &Path,
    purpose: MapsFor,
) -> Result<EncodeInput> {
    let specs = specs_for(scene, set, purpose)?;
    let samples = scene.orbit.sample_count();
    let mut textures = Vec::new();
    for (index, spec) in specs.iter().enumerate() {
        let layout = spec.layout();
        let (w, h) = layout.level_size(0);
        let channels = spec.layer.channels();
        let leaf = LeafLayout {
            width: w,
            height: h,
            faces: layout.faces(),
            mips: layout.levels(),
            channels: channels as u32,
        };
        let id = TextureId {
            object: index as u32,
            layer: 0,
        };
        let mut texture = ParamTexture::zeroed(id, orbit_grid(&scene.orbit), leaf, 1.0);
        let mut rows = 0u64;
        for k in 0..samples {
            let map = read_checked(infer_dir, k, index, spec)?;
            for (i, texel) in texture
                .sample_mut(k as usize)
                .chunks_exact_mut(channels)
                .enumerate()
            {
                for (ch, v) in texel.iter_mut().enumerate() {
                    *v = map[ch][i];
                }
            }
            // Saturating: the reports are plain JSON a user may have edited.
            rows = rows.saturating_add(sample_rows(&sample_dir(infer_dir, k), &spec.name()));
        }
        // Rate allocation weighs errors by screen area (thesis ch. 4).
        texture.screen_area = (rows as f32 / samples as f32).max(1.0);
        textures.push(texture);
    }
    Ok(EncodeInput { textures })
}

/// One map's channels, verified against its key record.
fn read_checked(dir: &Path, k: u32, spec_index: usize, spec: &MapSpec) -> Result<Vec<Vec<f32>>> {
    let path = map_path(dir, k, &spec.object, spec.layer);
    let bad = |why: String| BadMap {
        sample: k,
        spec: spec_index,
        path: path.clone(),
        why,
    };
    let bytes = inference::key::read_verified(&path).map_err(bad)?;
    let map = parse_map(&bytes, &path, &spec.layout(), spec.layer.channels())
        .map_err(|e| bad(e.to_string()))?;
    if let Some(v) = map.iter().flatten().find(|v| v.abs() > F16_MAX) {
        return Err(bad(format!(
            "{}: holds {v:e}, beyond what playback's f16 textures hold (±{F16_MAX})",
            path.display()
        ))
        .into());
    }
    Ok(map)
}

/// Pixels the layer covered in a sample (from its report.json), 0 if unknown.
fn sample_rows(sample_dir: &Path, layer: &str) -> u64 {
    std::fs::read(sample_dir.join("report.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|r| {
            r["layers"]
                .as_array()?
                .iter()
                .find(|l| l["name"] == layer)?["rows"]
                .as_u64()
        })
        .unwrap_or(0)
}

/// What an encode made.
pub struct Encoded {
    pub bytes: u64,
    pub raw_bytes: u64,
    pub ratio: f64,
    /// The worst texture's PSNR after decoding (the codec's definition).
    pub worst_psnr_db: f64,
    pub seconds: f64,
    /// Why the size differs from the target asked for, if it does.
    pub note: Option<String>,
}

/// Encodes `input` at `target` into `out` (atomically, with a key record
/// `key`), growing the budget until every texture decodes to at least
/// [`MIN_TEXTURE_PSNR_DB`]. Refuses to replace a file that is not the
/// engine's. `inputs_s`, the seconds the maps cost to make when known
/// (`compile::infer::inputs_budget`), plus the encode's own are recorded
/// as the container's compile time.
pub fn encode_to(
    input: &EncodeInput,
    target: Target,
    out: &Path,
    key: &Key,
    inputs_s: Option<f64>,
) -> Result<Encoded> {
    check_overwrite_keyed(out)?;
    let start = std::time::Instant::now();
    let raw = input.raw_bytes();
    let mut target = target;
    let mut note = None;
    loop {
        let (bytes, report) = match codec::encode(input, target, &EncodeOptions::default()) {
            Err(codec::CodecError::BudgetTooSmall { minimum, .. }) => {
                note = Some(format!(
                    "maps too small for the ratio asked: {minimum} bytes, the least the codec writes"
                ));
                target = Target::Bytes(minimum);
                continue;
            }
            r => r.with_context(|| format!("encoding {}", out.display()))?,
        };
        let container = codec::Container::from_bytes(bytes.clone())?;
        let worst = worst_psnr(&container, input)?;
        if worst >= MIN_TEXTURE_PSNR_DB {
            let seconds = start.elapsed().as_secs_f64();
            crate::util::files::write(out, &bytes)?;
            inference::key::write_record_timed(out, key, inputs_s.map(|s| s + seconds))?;
            return Ok(Encoded {
                bytes: report.bytes,
                raw_bytes: report.raw_bytes,
                ratio: report.ratio,
                worst_psnr_db: worst,
                seconds,
                note,
            });
        }
        let next = report.bytes.saturating_mul(2);
        if next > raw / 2 {
            bail!(
                "{}: the maps decode to {worst:.1} dB at {} bytes (need ≥ {MIN_TEXTURE_PSNR_DB} dB) and no size under half the raw maps holds that",
                out.display(),
                report.bytes
            );
        }
        note = Some(format!(
            "at {} bytes a texture decoded to {worst:.1} dB (< {MIN_TEXTURE_PSNR_DB} dB): encoded again with more bytes",
            report.bytes
        ));
        target = Target::Bytes(next);
    }
}

/// The lowest PSNR over the container's textures against `input`.
fn worst_psnr(container: &codec::Container, input: &EncodeInput) -> Result<f64> {
    let mut cache = codec::DecodeCache::default();
    let mut worst = f64::INFINITY;
    for t in &input.textures {
        let mut acc = PsnrAccum::default();
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s in 0..t.grid.len() as u32 {
            let at = t.grid.sample_at(s);
            cache.decode_leaf_all(container, t.id.object, t.id.layer, at, &mut out)?;
            cache.end_frame();
            acc.add(t.sample(s as usize), t.layout.channels as usize, &out, 4);
        }
        worst = worst.min(acc.psnr_db());
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ratio_must_be_above_one_and_at_most_100_000() {
        for ok in [1.000_001, 20.0, 384.0, 100_000.0] {
            assert!(check_ratio(ok).is_ok(), "{ok}");
        }
        for bad in [
            1.0,
            0.5,
            0.0,
            -384.0,
            100_001.0,
            1e9,
            f64::INFINITY,
            f64::NAN,
        ] {
            let e = check_ratio(bad).expect_err("refused");
            let want = format!("--ratio {bad}: expected a compression ratio above 1 and at most");
            assert!(e.to_string().starts_with(&want), "{e}");
        }
    }

    #[test]
    fn a_map_without_its_record_is_named_once() {
        let scene = inference::scene::Scene::load("teapot").expect("built-in scene");
        let dir = tempfile::tempdir().expect("tempdir");
        let e =
            load_input(&scene, MapSet::Scene, dir.path(), MapsFor::Encode).expect_err("no maps");
        let bad = e.downcast_ref::<BadMap>().expect("a BadMap");
        let text = format!("{e:#}");
        let path = bad.path.display().to_string();
        assert_eq!(text, format!("{path}: no record of how it was made"));
    }

    #[test]
    fn rings_are_a_2d_grid_whose_linear_order_is_the_sample_order() {
        let mut scene = inference::scene::Scene::load("teapot").expect("built-in scene");
        // The shipped rings skip lines: one sequence, ring after ring.
        assert_eq!(
            orbit_grid(&scene.orbit),
            ParamGrid::one_d(scene.orbit.sample_count())
        );
        scene.orbit.rings = 1;
        assert_eq!(
            orbit_grid(&scene.orbit),
            ParamGrid::one_d(scene.orbit.samples)
        );
        scene.orbit.samples = 4;
        scene.orbit.rings = 3;
        scene.orbit.ring_line_every = 1;
        let grid = orbit_grid(&scene.orbit);
        assert_eq!(grid, ParamGrid::two_d(4, 3));
        // Grid dimension 0 is the azimuth line, dimension 1 the ring.
        for k in 0..scene.orbit.sample_count() {
            let [line, ring] = grid.sample_at(k);
            let (azimuth, elevation) = scene.orbit.sample_angles(k);
            assert_eq!(azimuth, scene.orbit.sample_angles(line).0, "sample {k}");
            assert_eq!(
                elevation,
                scene.orbit.sample_angles(4 * ring).1,
                "sample {k}"
            );
        }
        assert_ne!(
            scene.orbit.sample_angles(4).1,
            scene.orbit.sample_angles(0).1
        );
        let key =
            |grid| crate::compile::container_key([].iter(), codec::Target::Ratio(384.0), grid);
        assert_eq!(
            key(ParamGrid::one_d(12)),
            key(ParamGrid::one_d(100)),
            "1D keys unchanged"
        );
        assert_ne!(key(ParamGrid::two_d(4, 3)), key(ParamGrid::one_d(12)));
    }
}
