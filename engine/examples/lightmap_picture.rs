//! A light map's finest level as a picture (each map scaled by its own
//! brightest texel), several side by side: what the room pass multiplies
//! the albedo by, where a solve's artifacts show plainly.
//!
//! ```sh
//! cargo run --release -p engine --example lightmap_picture -- OUT.png \
//!     assets/compiled/teapot/room/floor.light.exr [OTHER.light.exr …]
//! ```
//! Each `NAME.light.exr` needs its layout `NAME.light.json` beside it (the
//! files `engine compile` writes under `<out>/room/`).

use anyhow::{Context, Result, bail};
use inference::trace::output::read_exr;
use std::path::Path;

/// Level 0 of one light map as linear RGBA scaled to its maximum, with its size.
fn level0(path: &Path) -> Result<(usize, usize, Vec<[f32; 4]>)> {
    let json = path.with_extension("json");
    let layout: serde_json::Value = serde_json::from_slice(
        &std::fs::read(&json).with_context(|| format!("reading {}", json.display()))?,
    )
    .with_context(|| format!("{}: not JSON", json.display()))?;
    let size = |k: &str| layout[k].as_u64().map(|v| v as usize);
    let (Some(w), Some(h)) = (size("width"), size("height")) else {
        bail!("{}: expected width and height", json.display());
    };
    let layers = read_exr(path).with_context(|| format!("reading {}", path.display()))?;
    let Some((_, channels)) = layers.iter().find(|(n, _)| n == "mip0") else {
        bail!("{}: no mip0 layer", path.display());
    };
    let get = |c: &str| {
        channels
            .iter()
            .find(|(n, v)| n == c && v.len() == w * h)
            .map(|(_, v)| v)
            .with_context(|| format!("{}: mip0 lacks {c} of {w}x{h}", path.display()))
    };
    let (r, g, b) = (get("R")?, get("G")?, get("B")?);
    let max = r.iter().chain(g).chain(b).fold(1e-12f32, |m, &v| m.max(v));
    let pixels = (0..w * h)
        .map(|i| [r[i] / max, g[i] / max, b[i] / max, 1.0])
        .collect();
    Ok((w, h, pixels))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, maps @ ..] = args.as_slice() else {
        bail!("usage: lightmap_picture OUT.png LIGHT.exr [LIGHT.exr …]");
    };
    if maps.is_empty() {
        bail!("usage: lightmap_picture OUT.png LIGHT.exr [LIGHT.exr …]");
    }
    let levels = maps
        .iter()
        .map(|m| level0(Path::new(m)))
        .collect::<Result<Vec<_>>>()?;
    let (w, h) = (levels[0].0, levels[0].1);
    if levels.iter().any(|l| (l.0, l.1) != (w, h)) {
        bail!("the light maps differ in size; expected one layout");
    }
    let frames: Vec<&[[f32; 4]]> = levels.iter().map(|l| &l.2[..]).collect();
    engine::eval::pictures::frames_in_a_row(Path::new(out), &frames, w as u32, h as u32)
}
