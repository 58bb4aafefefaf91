//! The SH maps through the codec: the k signed coefficient planes as one
//! parameterized texture over a 1D grid of k samples (one plane each, RGB,
//! no MIPs), encoded at a ratio and cached as a container beside the raw
//! maps (`sh_…_r<ratio>.ptxc` with its key record); playback and the
//! scores use the decoded planes. The planes are different functions, so
//! the pyramid over the parameter finds little to share between them; the
//! gain is the per-plane transform coding.

use anyhow::{Context, Result};
use codec::input::{EncodeInput, LeafLayout, ParamGrid, ParamTexture, TextureId};
use codec::{Container, EncodeOptions, Target};
use inference::key::{Freshness, Key};
use inference::relight::ShMaps;
use std::path::{Path, PathBuf};

use crate::util::files;

/// The ratio `engine relight` and `engine eval` store the maps at.
pub const DEFAULT_RATIO: f64 = 20.0;

/// The maps as decoded from their container, and what it cost.
pub struct CompressedMaps {
    pub maps: ShMaps,
    pub path: PathBuf,
    pub bytes: u64,
    /// Read from the cache (not encoded this run).
    pub cached: bool,
}

/// The encoder's input: plane `i` is sample `i`.
fn input(maps: &ShMaps) -> Result<EncodeInput> {
    let p = maps.panorama;
    let layout = LeafLayout {
        width: p.width,
        height: p.height,
        faces: 1,
        mips: 1,
        channels: 3,
    };
    let id = TextureId {
        object: 0,
        layer: 0,
    };
    let mut texture = ParamTexture::zeroed(id, ParamGrid::one_d(maps.k as u32), layout, 1.0);
    for i in 0..maps.k {
        texture.sample_mut(i).copy_from_slice(maps.plane(i));
    }
    Ok(EncodeInput {
        textures: vec![texture],
    })
}

/// The codec's options for SH planes: no gamma compensation (gamma 1),
/// since a relit pixel's error is the planes' absolute errors weighted by
/// `Y_i(L)`, not a radiance a display compresses.
fn options() -> EncodeOptions {
    EncodeOptions {
        gamma: 1.0,
        ..EncodeOptions::default()
    }
}

/// Decodes every plane of `container` into maps of `like`'s shape.
fn decode(container: &Container, like: &ShMaps) -> Result<ShMaps> {
    let mut maps = ShMaps::zeros(like.panorama, like.k);
    let texels = like.panorama.texels();
    let mut rgba = vec![0.0f32; texels * 4];
    let mut cache = codec::DecodeCache::default();
    let n = texels * 3;
    for i in 0..like.k {
        cache.decode_leaf_all(container, 0, 0, [i as u32, 0], &mut rgba)?;
        let plane = &mut maps.coeffs[i * n..(i + 1) * n];
        for (c, t) in plane.chunks_exact_mut(3).zip(rgba.chunks_exact(4)) {
            c.copy_from_slice(&t[..3]);
        }
    }
    Ok(maps)
}

/// `maps` (cached raw under `raw_path` with key `raw_key`) encoded at
/// `ratio`:1 and decoded: read from the cached container when its key
/// matches, else encoded and cached.
pub fn compressed(
    maps: &ShMaps,
    raw_path: &Path,
    raw_key: &Key,
    ratio: f64,
) -> Result<CompressedMaps> {
    crate::compile::encode::check_ratio(ratio)?;
    let stem = raw_path
        .file_stem()
        .and_then(|s| s.to_str())
        .context("relight: the SH maps' cache has no file name")?;
    let path = raw_path.with_file_name(format!("{stem}_r{ratio}.ptxc"));
    let key = raw_key
        .clone()
        .with("codec ratio", ratio.to_bits())
        .with("codec format", u64::from(codec::FORMAT_VERSION))
        .with("codec gamma", u64::from(options().gamma.to_bits()));
    if matches!(inference::key::freshness(&path, &key), Freshness::Fresh) {
        // Opening names the file; decoding is told it.
        match Container::open(&path)
            .map_err(anyhow::Error::from)
            .and_then(|c| decode(&c, maps).with_context(|| path.display().to_string()))
        {
            Ok(decoded) => {
                let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
                return Ok(CompressedMaps {
                    maps: decoded,
                    path,
                    bytes,
                    cached: true,
                });
            }
            Err(e) => eprintln!("{e:#}: rebuilding it"),
        }
    }
    files::check_overwrite_keyed(&path)?;
    let (bytes, _) = codec::encode(&input(maps)?, Target::Ratio(ratio), &options())
        .with_context(|| format!("encoding the SH maps at {ratio}:1"))?;
    let container = Container::from_bytes(bytes.clone())?;
    let decoded = decode(&container, maps)?;
    files::write(&path, &bytes)?;
    inference::key::write_record(&path, &key)?;
    Ok(CompressedMaps {
        maps: decoded,
        path,
        bytes: bytes.len() as u64,
        cached: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use inference::relight::Panorama;

    /// Smooth signed planes, each a different function.
    fn maps() -> ShMaps {
        let panorama = Panorama {
            width: 64,
            height: 16,
        };
        let mut m = ShMaps::zeros(panorama, 9);
        let n = panorama.texels() * 3;
        for (j, v) in m.coeffs.iter_mut().enumerate() {
            let (i, t) = (j / n, (j % n) / 3);
            let (x, y) = ((t % 64) as f32 / 64.0, (t / 64) as f32 / 16.0);
            *v = (0.5 / (i + 1) as f32) * ((i as f32 + 1.0) * 3.0 * x + y * 2.0).sin();
        }
        m
    }

    #[test]
    fn the_planes_round_trip_through_the_codec_and_the_cache() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let raw = dir.path().join("sh_64x16_grid5x9.bin");
        let key = Key::new().with("test", 1);
        let m = maps();
        let first = compressed(&m, &raw, &key, 20.0)?;
        assert!(!first.cached && first.path.is_file());
        assert!(
            first.bytes < (m.coeffs.len() * 4 / 10) as u64,
            "{} bytes",
            first.bytes
        );
        let peak = m
            .coeffs
            .iter()
            .fold(0.0f64, |a, v| a.max(f64::from(v.abs())));
        let mse = m
            .coeffs
            .iter()
            .zip(&first.maps.coeffs)
            .map(|(x, y)| f64::from(x - y).powi(2))
            .sum::<f64>()
            / m.coeffs.len() as f64;
        let db = 10.0 * (peak * peak / mse).log10();
        assert!(db > 35.0, "{db:.2} dB at 20:1 (40.0 measured)");
        let again = compressed(&m, &raw, &key, 20.0)?;
        assert!(again.cached);
        assert_eq!(again.maps, first.maps);
        // A damaged container is rebuilt, not trusted.
        std::fs::write(&first.path, b"not a container")?;
        let rebuilt = compressed(&m, &raw, &key, 20.0)?;
        assert!(!rebuilt.cached);
        assert_eq!(rebuilt.maps, first.maps);
        assert!(compressed(&m, &raw, &key, 0.5).is_err());
        Ok(())
    }
}
