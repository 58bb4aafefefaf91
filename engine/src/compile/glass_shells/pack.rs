//! The per-sample shell maps compressed by the codec, as the PEM's maps
//! are: one RGB parameter texture over the shell samples (a 1D grid),
//! cached as `glass/room_shells.ptxc` under a key of every map it holds.
//! Playback decodes every sample once, at load.

use super::SampleShells;
use anyhow::{Context, Result, bail};
use codec::{
    Container, DecodeCache, EncodeInput, EncodeOptions, LeafLayout, ParamGrid, ParamTexture,
    Target, TextureId,
};
use half::f16;
use inference::key::Key;
use std::path::{Path, PathBuf};

/// Raw f32 bytes ÷ container bytes.
pub const SHELL_RATIO: f64 = 200.0;
/// Bumped when what the container holds changes.
const VERSION: u64 = 1;

pub fn container_path(out: &Path) -> PathBuf {
    crate::glass::shell::shell_path(out).with_file_name("room_shells.ptxc")
}

/// The container's key: each map's key, the ratio, the codec's format.
pub fn container_key(map_keys: &[Key]) -> Key {
    let mut key = Key::new()
        .with("shell container", VERSION)
        .with("ratio", SHELL_RATIO.to_bits())
        .with("codec format", u64::from(codec::FORMAT_VERSION));
    for (i, k) in map_keys.iter().enumerate() {
        key = key.with(&format!("sample {i}"), k.hash());
    }
    key
}

/// The maps' layout: `size`² cube faces with every MIP level, RGB.
fn leaf(size: u32) -> LeafLayout {
    LeafLayout {
        width: size,
        height: size,
        faces: 6,
        mips: LeafLayout::max_mips(size, size),
        channels: 3,
    }
}

/// `shells` compressed `ratio`:1 into a container (bytes).
pub fn encode(shells: &SampleShells, size: u32, ratio: f64) -> Result<Vec<u8>> {
    let layout = leaf(size);
    let id = TextureId {
        object: 0,
        layer: 0,
    };
    let grid = ParamGrid::one_d(shells.maps.len() as u32);
    let mut texture = ParamTexture::zeroed(id, grid, layout, 1.0);
    for (k, map) in shells.maps.iter().enumerate() {
        let halves: &[f16] = bytemuck::try_cast_slice(map)
            .map_err(|e| anyhow::anyhow!("shell map of sample {k}: {e}"))?;
        let sample = texture.sample_mut(k);
        if halves.len() / 4 * 3 != sample.len() {
            bail!(
                "shell map of sample {k}: {} texels, expected {}",
                halves.len() / 4,
                sample.len() / 3
            );
        }
        for (texel, h) in sample.chunks_exact_mut(3).zip(halves.chunks_exact(4)) {
            for c in 0..3 {
                texel[c] = h[c].to_f32();
            }
        }
    }
    let input = EncodeInput {
        textures: vec![texture],
    };
    let options = EncodeOptions::default();
    let encoded = match codec::encode(&input, Target::Ratio(ratio), &options) {
        // Maps so small that the ratio leaves less than the container's
        // fixed part: twice that part.
        Err(codec::CodecError::BudgetTooSmall { minimum, .. }) => {
            codec::encode(&input, Target::Bytes(2 * minimum), &options)
        }
        other => other,
    };
    let (bytes, _) = encoded.context("compressing the per-sample shell maps")?;
    Ok(bytes)
}

/// Every sample of a container [`encode`] made, decoded to f16 RGBA bytes
/// (the maps' playback form), at `azimuths`.
pub fn decode(bytes: Vec<u8>, azimuths: Vec<f32>, file: &Path) -> Result<SampleShells> {
    let bad = |e: codec::CodecError| anyhow::anyhow!("{}: {e}", file.display());
    let c = Container::from_bytes(bytes).map_err(bad)?;
    let t = c
        .textures()
        .first()
        .with_context(|| format!("{}: no texture", file.display()))?;
    if t.grid.len() != azimuths.len() {
        bail!(
            "{}: {} samples, expected {}",
            file.display(),
            t.grid.len(),
            azimuths.len()
        );
    }
    let mut cache = DecodeCache::default();
    let mut maps = Vec::with_capacity(azimuths.len());
    for k in 0..azimuths.len() as u32 {
        let mut out = vec![f16::ZERO; t.layout.texels() * 4];
        cache
            .decode_leaf_all(&c, 0, 0, [k, 0], &mut out)
            .map_err(bad)?;
        maps.push(bytemuck::cast_slice(&out).to_vec());
    }
    Ok(SampleShells { azimuths, maps })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth map of `size`² per face, varying with `k`, as f16 RGBA bytes.
    fn map(size: u32, k: usize) -> Vec<u8> {
        let texels = leaf(size).texels();
        (0..texels)
            .flat_map(|i| {
                let x = 0.5 + 0.4 * (i as f32 * 0.002).sin();
                [x, 0.5 * x + 0.1 * k as f32, 1.0 - x, 1.0].map(f16::from_f32)
            })
            .flat_map(f16::to_le_bytes)
            .collect()
    }

    #[test]
    fn packed_shells_decode_close_with_opaque_alpha() {
        let shells = SampleShells {
            azimuths: vec![0.0, 10.0, 20.0],
            maps: (0..3).map(|k| map(16, k)).collect(),
        };
        // Tiny maps: a lower ratio than the shipped one, above the
        // container's minimum size.
        let bytes = encode(&shells, 16, 20.0).expect("encode");
        // At the shipped ratio they get twice the container's fixed part.
        let small = encode(&shells, 16, SHELL_RATIO).expect("encode at the shipped ratio");
        assert!(small.len() > bytes.len() / 20, "{} bytes", small.len());
        let raw: usize = shells.maps.iter().map(Vec::len).sum();
        assert!(bytes.len() * 4 < raw, "{} bytes for {raw}", bytes.len());
        let file = Path::new("room_shells.ptxc");
        let back = decode(bytes.clone(), shells.azimuths.clone(), file).expect("decode");
        assert_eq!(back.azimuths, shells.azimuths);
        for (a, b) in shells.maps.iter().zip(&back.maps) {
            let a: &[f16] = bytemuck::cast_slice(a);
            let b: &[f16] = bytemuck::cast_slice(b);
            assert_eq!(a.len(), b.len());
            let (mut se, mut n) = (0.0f64, 0usize);
            for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
                assert_eq!(q[3], f16::ONE, "alpha");
                for c in 0..3 {
                    se += f64::from(p[c].to_f32() - q[c].to_f32()).powi(2);
                    n += 1;
                }
            }
            let psnr = -10.0 * (se / n as f64).log10();
            assert!(psnr > 30.0, "{psnr:.1} dB");
        }
        // A container of other samples is refused, naming the file.
        let e = decode(bytes, vec![0.0], file).expect_err("sample count");
        assert!(e.to_string().contains("room_shells.ptxc"), "{e}");
    }
}
