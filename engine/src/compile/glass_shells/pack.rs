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

/// Where the layered shells' per-sample maps are cached under `out`.
pub fn layers_container_path(out: &Path) -> PathBuf {
    crate::glass::shell::shell_path(out).with_file_name("layer_shells.ptxc")
}

/// The maps' layout: `size`² cube faces with every MIP level, `channels`
/// (3: RGB; 4: premultiplied RGBA, an inner shell layer).
fn leaf(size: u32, channels: u32) -> LeafLayout {
    LeafLayout {
        width: size,
        height: size,
        faces: 6,
        mips: LeafLayout::max_mips(size, size),
        channels,
    }
}

/// One parameter texture over the samples of `maps` (f16 RGBA bytes each),
/// keeping `channels` of each texel; texture `layer` of object 0.
fn texture(layer: u32, maps: &[Vec<u8>], size: u32, channels: u32) -> Result<ParamTexture> {
    let layout = leaf(size, channels);
    let id = TextureId { object: 0, layer };
    let grid = ParamGrid::one_d(maps.len() as u32);
    let mut texture = ParamTexture::zeroed(id, grid, layout, 1.0);
    let n = channels as usize;
    for (k, map) in maps.iter().enumerate() {
        let halves: &[f16] = bytemuck::try_cast_slice(map)
            .map_err(|e| anyhow::anyhow!("shell map {layer} of sample {k}: {e}"))?;
        let sample = texture.sample_mut(k);
        if halves.len() / 4 * n != sample.len() {
            bail!(
                "shell map {layer} of sample {k}: {} texels, expected {}",
                halves.len() / 4,
                sample.len() / n
            );
        }
        for (texel, h) in sample.chunks_exact_mut(n).zip(halves.chunks_exact(4)) {
            for c in 0..n {
                texel[c] = h[c].to_f32();
            }
        }
    }
    Ok(texture)
}

/// `shells` compressed `ratio`:1 into a container (bytes).
pub fn encode(shells: &SampleShells, size: u32, ratio: f64) -> Result<Vec<u8>> {
    encode_textures(vec![texture(0, &shells.maps, size, 3)?], ratio)
}

/// Layered shells' per-sample maps (`layers[k][s]`: layer `k`, nearest
/// first, of sample `s`) compressed `ratio`:1 into one container: the
/// inner layers premultiplied RGBA, the outermost RGB (it is opaque).
pub fn encode_layers(layers: &[Vec<Vec<u8>>], size: u32, ratio: f64) -> Result<Vec<u8>> {
    let n = layers.len();
    let textures = (layers.iter().enumerate())
        .map(|(k, maps)| texture(k as u32, maps, size, if k + 1 < n { 4 } else { 3 }))
        .collect::<Result<Vec<_>>>()?;
    encode_textures(textures, ratio)
}

fn encode_textures(textures: Vec<ParamTexture>, ratio: f64) -> Result<Vec<u8>> {
    let input = EncodeInput { textures };
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
    let mut layers = decode_layers(bytes, azimuths.len(), 1, file)?;
    let maps = layers.pop().unwrap_or_default();
    Ok(SampleShells { azimuths, maps })
}

/// Every sample of every layer of a container [`encode_layers`] made with
/// `layers` layers of `samples` samples: `[layer][sample]`, f16 RGBA bytes.
pub fn decode_layers(
    bytes: Vec<u8>,
    samples: usize,
    layers: usize,
    file: &Path,
) -> Result<Vec<Vec<Vec<u8>>>> {
    let bad = |e: codec::CodecError| anyhow::anyhow!("{}: {e}", file.display());
    let c = Container::from_bytes(bytes).map_err(bad)?;
    if c.textures().len() != layers {
        bail!(
            "{}: {} textures, expected {layers} (one per shell layer)",
            file.display(),
            c.textures().len()
        );
    }
    let mut cache = DecodeCache::default();
    (0..layers as u32)
        .map(|k| {
            let t = &c.textures()[c.texture_index(0, k).map_err(bad)?];
            if t.grid.len() != samples {
                bail!(
                    "{}: {} samples, expected {samples}",
                    file.display(),
                    t.grid.len()
                );
            }
            (0..samples as u32)
                .map(|s| {
                    let mut out = vec![f16::ZERO; t.layout.texels() * 4];
                    cache
                        .decode_leaf_all(&c, t.id.object, t.id.layer, [s, 0], &mut out)
                        .map_err(bad)?;
                    Ok(bytemuck::cast_slice(&out).to_vec())
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth map of `size`² per face, varying with `k`, as f16 RGBA bytes.
    fn map(size: u32, k: usize) -> Vec<u8> {
        let texels = leaf(size, 3).texels();
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

    #[test]
    fn packed_layers_keep_the_inner_coverage_and_an_opaque_outermost() {
        // Two layers of two samples: the inner one's alpha varies.
        let texels = leaf(16, 4).texels();
        let inner = |k: usize| -> Vec<u8> {
            (0..texels)
                .flat_map(|i| {
                    let a = 0.5 + 0.4 * (i as f32 * 0.003 + k as f32).sin();
                    [0.8 * a, 0.2 * a, 0.1 * a, a].map(f16::from_f32)
                })
                .flat_map(f16::to_le_bytes)
                .collect()
        };
        let layers = vec![vec![inner(0), inner(1)], vec![map(16, 0), map(16, 1)]];
        let bytes = encode_layers(&layers, 16, 20.0).expect("encode");
        let file = Path::new("layer_shells.ptxc");
        let back = decode_layers(bytes.clone(), 2, 2, file).expect("decode");
        assert_eq!(back.len(), 2);
        for (k, (a, b)) in layers
            .iter()
            .flatten()
            .zip(back.iter().flatten())
            .enumerate()
        {
            let a: Vec<f16> = bytemuck::pod_collect_to_vec(a);
            let b: Vec<f16> = bytemuck::pod_collect_to_vec(b);
            assert_eq!(a.len(), b.len());
            let mut worst = 0.0f32;
            for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
                if k >= 2 {
                    assert_eq!(q[3], f16::ONE, "the outermost layer is opaque");
                }
                for c in 0..4 {
                    worst = worst.max((p[c].to_f32() - q[c].to_f32()).abs());
                }
            }
            assert!(worst < 0.1, "map {k}: off by {worst}");
        }
        // Another count of layers or samples is refused, naming the file.
        for (samples, n) in [(3, 2), (2, 3)] {
            let e = decode_layers(bytes.clone(), samples, n, file).expect_err("counts");
            assert!(e.to_string().contains("layer_shells.ptxc"), "{e}");
        }
    }
}
