//! Whole-frame scores of one frame against another, as `engine eval`
//! takes them (display-referred PSNR and FLIP over every pixel), and
//! optionally a picture: reference | test | difference (×4, display-referred).
//!
//! ```sh
//! cargo run --release -p engine --example frame_compare -- REF.exr TEST.exr [OUT.png]
//! ```
//! Each EXR is a traced image (its `beauty` layer) or an engine frame
//! (`--exr`, its RGBA).

use anyhow::{Context, Result, bail};
use engine::eval::metrics::{display_psnr_masked, frame_scores};
use inference::trace::output::read_exr;
use std::path::Path;

fn frame(path: &Path) -> Result<(u32, u32, Vec<[f32; 4]>)> {
    let layers = read_exr(path).with_context(|| format!("reading {}", path.display()))?;
    let layer = layers
        .iter()
        .find(|(n, _)| n == "beauty")
        .or_else(|| layers.iter().find(|(_, c)| c.iter().any(|(n, _)| n == "R")))
        .with_context(|| format!("{}: no beauty or RGB layer", path.display()))?;
    let get = |c: &str| layer.1.iter().find(|(n, _)| n == c).map(|(_, v)| v);
    let (Some(r), Some(g), Some(b)) = (get("R"), get("G"), get("B")) else {
        bail!("{}: expected R, G, B", path.display());
    };
    let pixels: Vec<[f32; 4]> = (0..r.len()).map(|i| [r[i], g[i], b[i], 1.0]).collect();
    // Frames here are 4:3 (the engine's default); the size follows.
    let height = ((pixels.len() as f64 * 3.0 / 4.0).sqrt()).round() as u32;
    let width = pixels.len() as u32 / height.max(1);
    if (width * height) as usize != pixels.len() {
        bail!(
            "{}: not a 4:3 frame ({} pixels)",
            path.display(),
            pixels.len()
        );
    }
    Ok((width, height, pixels))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [reference, test, rest @ ..] = args.as_slice() else {
        bail!("usage: frame_compare REF.exr TEST.exr [OUT.png]");
    };
    let (w, h, a) = frame(Path::new(reference))?;
    let (w2, h2, b) = frame(Path::new(test))?;
    if (w, h) != (w2, h2) {
        bail!("sizes differ: {w}x{h} and {w2}x{h2}");
    }
    let s = frame_scores(&a, &b, w, h)?;
    let mean = |f: &[[f32; 4]]| f.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / f.len() as f32;
    println!(
        "display PSNR {:.2} dB, FLIP {:.4}, mean test/ref {:.3}",
        s.psnr_db,
        s.flip,
        mean(&b) / mean(&a)
    );
    // Per object of a traced reference (its `<object>.mask` layers).
    let layers = read_exr(Path::new(reference)).unwrap_or_default();
    for (name, channels) in layers.iter().filter(|(n, _)| n.ends_with(".mask")) {
        let Some((_, mask)) = channels.first() else {
            continue;
        };
        let mask: Vec<bool> = mask.iter().map(|&m| m >= 0.5).collect();
        if let Some((db, share)) = display_psnr_masked(&a, &b, &mask)? {
            println!(
                "  {:<14} {db:6.2} dB ({:5.1}% of the frame's squared error)",
                name.trim_end_matches(".mask"),
                100.0 * share
            );
        }
    }
    if let Some(out) = rest.first() {
        let diff = engine::eval::metrics::display_difference(&a, &b, 4.0);
        engine::eval::pictures::frames_in_a_row(Path::new(out), &[&a, &b, &diff], w, h)?;
    }
    Ok(())
}
