//! Loads `engine infer --all` output (one EXR per sample and layer) into an
//! [`EncodeInput`], the way `engine/src/codec_cmd.rs::load_input` does,
//! without depending on the inference crate.

use std::path::Path;

use codec::{EncodeInput, LeafLayout, ParamGrid, ParamTexture, TextureId};
use exr::prelude::*;

/// (layer file stem, faces, channels), in the engine's container order.
pub const LAYERS: [(&str, u32, u32); 3] = [
    ("specular_distant", 6, 3),
    ("specular_local", 6, 4),
    ("ptm", 1, 3),
];

const CHANNELS: [&str; 4] = ["R", "G", "B", "A"];

/// Reads one map (parts `mip0..`, faces side by side) into `out`
/// (LeafLayout order, channels interleaved).
fn read_map(path: &Path, l: &LeafLayout, out: &mut [f32]) -> std::result::Result<(), String> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let ch = l.channels as usize;
    let faces = l.faces as usize;
    for mip in 0..l.mips {
        let name = format!("mip{mip}");
        let layer = image
            .layer_data
            .iter()
            .find(|p| p.attributes.layer_name.as_ref().map(Text::to_string) == Some(name.clone()))
            .ok_or_else(|| format!("{}: no part {name}", path.display()))?;
        let (w, h) = l.mip_size(mip);
        if layer.size != Vec2(w * faces, h) {
            return Err(format!(
                "{}: part {name} is {:?}",
                path.display(),
                layer.size
            ));
        }
        for (c, cname) in CHANNELS.iter().enumerate().take(ch) {
            let channel = layer
                .channel_data
                .list
                .iter()
                .find(|x| x.name.to_string() == *cname)
                .ok_or_else(|| format!("{}: {name} has no {cname}", path.display()))?;
            let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
            for y in 0..h {
                for face in 0..faces {
                    let o = l.texel_offset(face as u32, mip);
                    for x in 0..w {
                        out[(o + y * w + x) * ch + c] = values[(y * faces + face) * w + x];
                    }
                }
            }
        }
    }
    Ok(())
}

/// The scene's textures for samples `0..samples` of `dir` (`sample_XXXX/`),
/// object `object` (file prefix), cube size `size`. `layers` picks from
/// [`LAYERS`] by index.
pub fn load(
    dir: &Path,
    object: &str,
    size: u32,
    samples: u32,
    layers: &[usize],
) -> std::result::Result<EncodeInput, String> {
    let mut textures = Vec::new();
    for (k, &li) in layers.iter().enumerate() {
        let (stem, faces, channels) = LAYERS[li];
        let layout = LeafLayout {
            width: size,
            height: size,
            faces,
            mips: LeafLayout::max_mips(size, size),
            channels,
        };
        let mut t = ParamTexture::zeroed(
            TextureId {
                object: k as u32,
                layer: 0,
            },
            ParamGrid::one_d(samples),
            layout,
            1.0,
        );
        for s in 0..samples {
            let path = dir
                .join(format!("sample_{s:04}"))
                .join(format!("{object}.{stem}.exr"));
            read_map(&path, &layout, t.sample_mut(s as usize))?;
        }
        textures.push(t);
    }
    Ok(EncodeInput { textures })
}
