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
//!     SCENE DATA_DIR AZIMUTH ELEVATION REF_DIR [OUT.png]
//! ```
//! DATA_DIR holds the compiled shells (the main job's `--out`); REF_DIR
//! the traced references at 640×480, 16 spp (`engine eval`'s
//! `reference/` folder: the view is read from there, or traced into it).

use anyhow::{Context, Result, bail};
use engine::eval::metrics::{masked_flip, masked_psnr};
use engine::eval::reference::{References, View};
use engine::options::{Mode, PemOptions, RunPlace};
use engine::play::{Session, compile_context, setup_mode};
use inference::trace::TraceSettings;
use std::path::Path;

type Frame = Vec<[f32; 4]>;

/// Pixels whose layered and one-shell frames differ by more than this
/// (largest channel, linear) are where the layers change the frame.
const CHANGED: f32 = 0.01;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, data, az, el, ref_dir, rest @ ..] = args.as_slice() else {
        bail!("usage: glass_layers SCENE DATA_DIR AZIMUTH ELEVATION REF_DIR [OUT.png]");
    };
    let view = View::new(
        az.parse().context("AZIMUTH: expected degrees")?,
        el.parse().context("ELEVATION: expected degrees")?,
    );
    let place = RunPlace::compiled_in(scene, Path::new(data), (640, 480));
    let mut session = Session::open(&place)?;
    let (width, height) = session.renderer.size();
    let lens = session
        .scene
        .objects
        .iter()
        .find(|o| o.glass.is_some())
        .map(|o| o.name.clone())
        .context("the scene has no glass object")?;
    let settings = TraceSettings {
        width,
        height,
        spp: 16,
        ..TraceSettings::default()
    };
    let reference =
        References::new(&session.scene, Path::new(ref_dir), settings)?.get(view, &lens)?;
    let (traced, glass) = (&reference.beauty, &reference.mask);
    let eye = reference.eye;
    // One shell, then the layers (the split, then every triangle layered).
    let hybrid = |traced_shell: bool, session: &mut Session| -> Result<Vec<Frame>> {
        let pem = PemOptions {
            tau: Some(3.0),
            traced_shell,
            ..PemOptions::default()
        };
        let ctx = compile_context(&place, &session.scene, &session.out);
        let mut source = setup_mode(
            &ctx,
            &mut session.renderer,
            Mode::Hybrid,
            &pem,
            Default::default(),
        )?;
        let mut frames = vec![source.frame(&mut session.renderer, &session.scene, eye)?.1];
        if let Some(g) = session.renderer.glass.as_mut().filter(|_| !traced_shell) {
            println!(
                "{} of {} lens triangles read every layer",
                g.last.layered_triangles, g.last.triangles
            );
            g.read_every_layer_everywhere();
            frames.push(source.frame(&mut session.renderer, &session.scene, eye)?.1);
        }
        Ok(frames)
    };
    let one = hybrid(true, &mut session)?.remove(0);
    let [layered, every]: [Frame; 2] = hybrid(false, &mut session)?
        .try_into()
        .map_err(|_| anyhow::anyhow!("the scene plays no shell layers"))?;
    let differ = (every.iter().zip(&layered))
        .filter(|(a, b)| a[..3] != b[..3])
        .count();
    let largest = (every.iter().zip(&layered))
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    let db = masked_psnr(&every, &layered, glass)?.unwrap_or(f64::NAN);
    println!(
        "only the triangles an inner layer reaches read it: {differ} pixels differ from every triangle reading every layer, by at most {largest:.2e} ({db:.1} dB over the glass)"
    );
    let changed: Vec<bool> = (one.iter().zip(&layered).zip(glass))
        .map(|((a, b), &g)| g && (0..3).any(|c| (a[c] - b[c]).abs() > CHANGED))
        .collect();
    let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
    println!(
        "glass: {} pixels, of which the layers change {}",
        count(glass),
        count(&changed)
    );
    for (name, frame) in [("one shell", &one), ("layered shells", &layered)] {
        let score = |mask: &[bool]| -> Result<(f64, f64)> {
            let db = masked_psnr(traced, frame, mask)?.unwrap_or(f64::NAN);
            let flip = masked_flip(traced, frame, width, height, mask)?.unwrap_or(f64::NAN);
            Ok((db, flip))
        };
        let (g_db, g_flip) = score(glass)?;
        let (c_db, c_flip) = score(&changed)?;
        println!(
            "{name:>15}: glass {g_db:.2} dB, FLIP {g_flip:.4}; where the layers change it {c_db:.2} dB, FLIP {c_flip:.4}"
        );
    }
    if let Some(out) = rest.first() {
        write_crops(Path::new(out), &[&one, &layered, traced], glass, width)?;
    }
    Ok(())
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
