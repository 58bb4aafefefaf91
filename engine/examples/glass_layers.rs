//! Layered shells against the one room shell at one view of a glass
//! scene: both hybrid frames (τ = 3) scored against a traced reference
//! over the glass's pixels (linear PSNR and FLIP, as `engine eval`) and
//! over the pixels where the layers change the frame; the layered frame
//! against the same with every lens triangle reading every layer (what
//! drawing only the triangles an inner layer reaches changes); optionally
//! a picture of the glass, cropped: one shell | layered shells | tracer.
//!
//! ```sh
//! cargo run --release -p engine --example glass_layers -- \
//!     SCENE DATA_DIR AZIMUTH ELEVATION REF.exr [OUT.png]
//! ```
//! DATA_DIR holds the compiled shells (the main job's `--out`); REF.exr is
//! a traced view at the same azimuth, elevation and size (one of `engine
//! eval`'s `reference/` files), with the lens's `<object>.mask` layer.

use anyhow::{Context, Result, bail};
use engine::eval::metrics::{masked_flip, masked_psnr};
use engine::options::{Mode, PemOptions, RunPlace};
use engine::play::{Session, compile_context, setup_mode};
use inference::trace::output::read_exr;
use std::path::{Path, PathBuf};

type Frame = Vec<[f32; 4]>;

/// Pixels whose layered and one-shell frames differ by more than this
/// (largest channel, linear) are where the layers change the frame.
const CHANGED: f32 = 0.01;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, data, az, el, reference, rest @ ..] = args.as_slice() else {
        bail!("usage: glass_layers SCENE DATA_DIR AZIMUTH ELEVATION REF.exr [OUT.png]");
    };
    let (az, el): (f32, f32) = (
        az.parse().context("AZIMUTH: expected degrees")?,
        el.parse().context("ELEVATION: expected degrees")?,
    );
    let place = RunPlace {
        scene: scene.clone(),
        out: Some(PathBuf::from(data)),
        device: Default::default(),
        size: (640, 480),
        recompile: false,
    };
    let mut session = Session::open(&place)?;
    let (width, height) = session.renderer.size();
    let lens = session
        .scene
        .objects
        .iter()
        .find(|o| o.glass.is_some())
        .map(|o| o.name.clone())
        .context("the scene has no glass object")?;
    let (traced, glass) = read_reference(Path::new(reference), &lens, width * height)?;
    let eye = session.scene.orbit.eye(az, el);
    let mut frames = Vec::new();
    for traced_shell in [true, false] {
        let pem = PemOptions {
            tau: Some(3.0),
            traced_shell,
            ..PemOptions::default()
        };
        let ctx = compile_context(&place, &session.scene, &session.out);
        let mut source = setup_mode(&ctx, &mut session.renderer, Mode::Hybrid, &pem, 16)?;
        frames.push(source.frame(&mut session.renderer, &session.scene, eye)?.1);
        if let Some(g) = session.renderer.glass.as_ref().filter(|_| !traced_shell) {
            let s = g.last;
            println!(
                "{} of {} lens triangles read every layer",
                s.layered_triangles, s.triangles
            );
        }
        if !traced_shell {
            if let Some(g) = session.renderer.glass.as_mut() {
                g.read_every_layer_everywhere();
            }
            let every = source.frame(&mut session.renderer, &session.scene, eye)?.1;
            let differ = (every.iter().zip(&frames[1]))
                .filter(|(a, b)| a[..3] != b[..3])
                .count();
            let largest = (every.iter().zip(&frames[1]))
                .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
                .fold(0.0f32, f32::max);
            let db = masked_psnr(&every, &frames[1], &glass)?.unwrap_or(f64::NAN);
            println!(
                "only the triangles an inner layer reaches read it: {differ} pixels differ from every triangle reading every layer, by at most {largest:.2e} ({db:.1} dB over the glass)"
            );
        }
    }
    let changed: Vec<bool> = (frames[0].iter().zip(&frames[1]).zip(&glass))
        .map(|((a, b), &g)| g && (0..3).any(|c| (a[c] - b[c]).abs() > CHANGED))
        .collect();
    let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
    println!(
        "glass: {} pixels, of which the layers change {}",
        count(&glass),
        count(&changed)
    );
    for (name, frame) in ["one shell", "layered shells"].iter().zip(&frames) {
        let score = |mask: &[bool]| -> Result<(f64, f64)> {
            let db = masked_psnr(&traced, frame, mask)?.unwrap_or(f64::NAN);
            let flip = masked_flip(&traced, frame, width, height, mask)?.unwrap_or(f64::NAN);
            Ok((db, flip))
        };
        let (g_db, g_flip) = score(&glass)?;
        let (c_db, c_flip) = score(&changed)?;
        println!(
            "{name:>15}: glass {g_db:.2} dB, FLIP {g_flip:.4}; where the layers change it {c_db:.2} dB, FLIP {c_flip:.4}"
        );
    }
    if let Some(out) = rest.first() {
        let panels = [&frames[0], &frames[1], &traced];
        write_crops(Path::new(out), &panels, &glass, width)?;
    }
    Ok(())
}

/// The reference's beauty and the lens's coverage (≥ ½) of `pixels` pixels.
fn read_reference(path: &Path, lens: &str, pixels: u32) -> Result<(Frame, Vec<bool>)> {
    let layers = read_exr(path)?;
    let channel = |layer: &str, c: &str| {
        layers
            .iter()
            .find(|(n, _)| n == layer)
            .and_then(|(_, chs)| chs.iter().find(|(n, _)| n == c))
            .map(|(_, v)| v.clone())
            .with_context(|| format!("{}: no {layer}.{c}", path.display()))
    };
    let (r, g, b) = (
        channel("beauty", "R")?,
        channel("beauty", "G")?,
        channel("beauty", "B")?,
    );
    let mask = channel(&format!("{lens}.mask"), "Y")?;
    if r.len() != pixels as usize || mask.len() != r.len() {
        bail!("{}: expected {pixels} pixels", path.display());
    }
    let frame = (0..r.len()).map(|i| [r[i], g[i], b[i], 1.0]).collect();
    Ok((frame, mask.iter().map(|&m| m >= 0.5).collect()))
}

/// `panels` cropped to the bounds of `mask`, side by side, into `path`.
fn write_crops(path: &Path, panels: &[&Frame], mask: &[bool], width: u32) -> Result<()> {
    let w = width as usize;
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (x, y) = (i % w, i / w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    if x0 > x1 {
        bail!("the reference shows no glass");
    }
    let (cw, ch) = (x1 - x0 + 1, y1 - y0 + 1);
    let mut mosaic = vec![[0.0f32; 4]; panels.len() * cw * ch];
    for y in 0..ch {
        for (k, p) in panels.iter().enumerate() {
            let row = (y0 + y) * w + x0;
            let at = y * panels.len() * cw + k * cw;
            mosaic[at..at + cw].copy_from_slice(&p[row..row + cw]);
        }
    }
    engine::capture::write_png(path, (panels.len() * cw) as u32, ch as u32, &mosaic)?;
    Ok(())
}
