//! A picture of how views between rings blend: a piece of the teapot's
//! viewpoint grid (azimuth across, elevation up, the orbit at the bottom
//! with lines 1° apart, rings 10° and 20° above it with lines 4° apart),
//! each point coloured by the set of samples its view draws — the cells'
//! four corners on the left (`--view-blend bilinear`), the triangles'
//! three on the right (the default) — with the samples as black dots.
//!
//! ```sh
//! cargo run --release -p engine --example view_blend_picture -- OUT.png
//! ```

use anyhow::{Context, Result};
use inference::scene::{ViewBlend, ViewGrid};

/// Pixels per degree, and the piece of the grid drawn.
const SCALE: f32 = 24.0;
const AZIMUTHS: (f32, f32) = (28.0, 44.0);
const ELEVATIONS: (f32, f32) = (0.0, 20.0);
const GAP: u32 = 24;

fn main() -> Result<()> {
    let out = std::env::args()
        .nth(1)
        .context("usage: view_blend_picture OUT.png")?;
    let grid = ViewGrid {
        azimuths_deg: (0..100).map(|k| k as f32).collect(),
        elevations_deg: vec![0.0, 10.0, 20.0, 30.0],
        ring_line_every: 4,
        ..Default::default()
    };
    let w = ((AZIMUTHS.1 - AZIMUTHS.0) * SCALE) as u32 + 1;
    let h = ((ELEVATIONS.1 - ELEVATIONS.0) * SCALE) as u32 + 1;
    let mut img = image::RgbImage::from_pixel(2 * w + GAP, h, image::Rgb([255, 255, 255]));
    for (panel, rule) in [ViewBlend::Bilinear, ViewBlend::Triangles]
        .into_iter()
        .enumerate()
    {
        let x0 = panel as u32 * (w + GAP);
        for y in 0..h {
            for x in 0..w {
                let (az, el) = angles(x, y, h);
                let mut set: Vec<u32> = grid.blend_by(az, el, 1, true, rule).indices().collect();
                set.sort_unstable();
                img.put_pixel(x0 + x, y, pale(&set));
            }
        }
        for k in 0..grid.len() {
            let (az, el) = grid.angles(k);
            let inside = (AZIMUTHS.0..=AZIMUTHS.1).contains(&az)
                && (ELEVATIONS.0..=ELEVATIONS.1).contains(&el);
            if inside {
                let x = ((az - AZIMUTHS.0) * SCALE).round() as i64;
                let y = h as i64 - 1 - ((el - ELEVATIONS.0) * SCALE).round() as i64;
                dot(&mut img, x0 as i64 + x, y, x0, w);
            }
        }
    }
    img.save(&out).with_context(|| format!("writing {out}"))
}

/// The view angles at pixel (`x`, `y`) of a panel `h` pixels tall.
fn angles(x: u32, y: u32, h: u32) -> (f32, f32) {
    (
        AZIMUTHS.0 + x as f32 / SCALE,
        ELEVATIONS.0 + (h - 1 - y) as f32 / SCALE,
    )
}

/// A pale colour per set of samples (neighbouring sets differ).
fn pale(set: &[u32]) -> image::Rgb<u8> {
    let mut hash: u32 = 2_166_136_261;
    for &k in set {
        hash = (hash ^ k).wrapping_mul(16_777_619);
    }
    let c = |shift: u32| 150 + ((hash >> shift) & 0x5f) as u8;
    image::Rgb([c(0), c(8), c(16)])
}

/// A black dot at (`x`, `y`), clipped to the panel starting at `x0`.
fn dot(img: &mut image::RgbImage, x: i64, y: i64, x0: u32, w: u32) {
    for dy in -3..=3i64 {
        for dx in -3..=3i64 {
            let (px, py) = (x + dx, y + dy);
            let in_panel = px >= x0 as i64 && px < (x0 + w) as i64;
            if dx * dx + dy * dy <= 9 && in_panel && py >= 0 && py < img.height() as i64 {
                img.put_pixel(px as u32, py as u32, image::Rgb([0, 0, 0]));
            }
        }
    }
}
