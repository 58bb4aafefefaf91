//! The README's picture of the edge filter: one view of the default frame
//! without and with `--edge-filter` beside the traced reference, each
//! cropped to a piece of the teapot's outline and magnified (nearest
//! neighbour, so each pixel shows as a square); prints each frame's
//! whole-frame display PSNR.
//!
//! ```sh
//! cargo run --release -p engine --example edge_filter_picture -- \
//!     teapot DATA_DIR AZIMUTH ELEVATION REF.exr OUT.png X Y W H ZOOM
//! ```
//! DATA_DIR holds the compiled maps (the main job's `--out`); REF.exr is a
//! traced view at the same azimuth, elevation and size (e.g. one of
//! `engine eval`'s `reference/` files); X Y W H the crop in pixels.

use anyhow::{Context, Result, bail};
use engine::compile::infer::targets::target_pixels;
use engine::eval::metrics::frame_scores;
use engine::options::{Mode, PemOptions, RunPlace};
use engine::play::{Session, compile_context, setup_mode};
use inference::trace::output::read_exr;
use std::path::Path;

type Frame = Vec<[f32; 4]>;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, data, az, el, reference, out, crop @ ..] = args.as_slice() else {
        bail!("usage: edge_filter_picture SCENE DATA_DIR AZ EL REF.exr OUT.png X Y W H ZOOM");
    };
    let numbers: Vec<u32> = crop
        .iter()
        .map(|v| {
            v.parse()
                .with_context(|| format!("{v}: expected a whole number"))
        })
        .collect::<Result<_>>()?;
    let [x, y, w, h, zoom] = numbers[..] else {
        bail!("expected the crop as X Y W H ZOOM");
    };
    let (az, el): (f32, f32) = (
        az.parse().context("AZIMUTH: expected degrees")?,
        el.parse().context("ELEVATION: expected degrees")?,
    );
    let layers = read_exr(Path::new(reference))?;
    let place = RunPlace::compiled_in(scene, Path::new(data), (640, 480));
    let mut session = Session::open(&place)?;
    let (width, height) = session.renderer.size();
    let traced = target_pixels(&layers, "beauty", false, (width * height) as usize)
        .with_context(|| reference.clone())?;
    if x + w > width || y + h > height || zoom == 0 {
        bail!("{x} {y} {w} {h} {zoom}: expected a crop inside the {width}x{height} frame");
    }
    let eye = session.scene.orbit.eye(az, el);
    let mut crops = Vec::new();
    for edge_filter in [false, true] {
        let pem = PemOptions {
            edge_filter,
            ..PemOptions::default()
        };
        let ctx = compile_context(&place, &session.scene, &session.out);
        let mut source = setup_mode(
            &ctx,
            &mut session.renderer,
            Mode::LayeredPem,
            &pem,
            Default::default(),
        )?;
        let pixels = source.frame(&mut session.renderer, &session.scene, eye)?.1;
        let s = frame_scores(&traced, &pixels, width, height)?;
        println!(
            "edge filter {edge_filter}: whole frame {:.2} dB, FLIP {:.4}",
            s.psnr_db, s.flip
        );
        crops.push(cropped(&pixels, width, (x, y, w, h), zoom));
    }
    crops.push(cropped(&traced, width, (x, y, w, h), zoom));
    // Side by side, a 2-pixel black gap between.
    let (cw, ch) = (w * zoom, h * zoom);
    let total = 3 * cw + 4;
    let mut mosaic = vec![[0.0f32, 0.0, 0.0, 1.0]; (total * ch) as usize];
    for (k, c) in crops.iter().enumerate() {
        let left = k as u32 * (cw + 2);
        for row in 0..ch {
            let at = (row * total + left) as usize;
            let src = (row * cw) as usize;
            mosaic[at..at + cw as usize].copy_from_slice(&c[src..src + cw as usize]);
        }
    }
    engine::capture::write_png(Path::new(out), total, ch, &mosaic)?;
    Ok(())
}

/// The `(x, y, w, h)` piece of a `width`-wide frame, each pixel `zoom`
/// times larger.
fn cropped(frame: &[[f32; 4]], width: u32, (x, y, w, h): (u32, u32, u32, u32), zoom: u32) -> Frame {
    let mut out = Vec::with_capacity((w * h * zoom * zoom) as usize);
    for row in 0..h * zoom {
        for col in 0..w * zoom {
            let p = frame[((y + row / zoom) * width + x + col / zoom) as usize];
            out.push([p[0], p[1], p[2], 1.0]);
        }
    }
    out
}
