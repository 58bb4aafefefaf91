//! Pictures `engine eval` writes: every mode's frame of one view, cropped
//! around the reflector, side by side.

use anyhow::{Context, Result};
use std::path::Path;

/// One picture: each mode's frame cropped around the reflector, side by side.
pub fn side_by_side(
    path: &Path,
    pictures: &[(String, Vec<[f32; 4]>)],
    mask: &[bool],
    width: u32,
    height: u32,
) -> Result<()> {
    let (w, h) = (width as usize, height as usize);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (x, y) = (i % w, i / w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    if x0 > x1 {
        (x0, y0, x1, y1) = (0, 0, w - 1, h - 1);
    }
    let margin = 8;
    let (x0, y0) = (x0.saturating_sub(margin), y0.saturating_sub(margin));
    let (x1, y1) = ((x1 + margin).min(w - 1), (y1 + margin).min(h - 1));
    let (cw, ch) = (x1 - x0 + 1, y1 - y0 + 1);
    let n = pictures.len();
    let mut mosaic = vec![[0.0f32; 4]; cw * n * ch];
    for (k, (_, pixels)) in pictures.iter().enumerate() {
        for y in 0..ch {
            for x in 0..cw {
                mosaic[y * cw * n + k * cw + x] = pixels[(y0 + y) * w + x0 + x];
            }
        }
    }
    crate::capture::write_png(path, (cw * n) as u32, ch as u32, &mosaic)?;
    let labels: Vec<&str> = pictures.iter().map(|p| p.0.as_str()).collect();
    std::fs::write(path.with_extension("txt"), labels.join(" | ") + "\n")
        .with_context(|| format!("writing {}", path.with_extension("txt").display()))?;
    Ok(())
}

/// Whole frames of `width × height` side by side, left to right, as one PNG.
pub fn frames_in_a_row(path: &Path, frames: &[&[[f32; 4]]], width: u32, height: u32) -> Result<()> {
    let (w, h, n) = (width as usize, height as usize, frames.len());
    let mut mosaic = vec![[0.0f32; 4]; n * w * h];
    for (k, image) in frames.iter().enumerate() {
        if image.len() != w * h {
            anyhow::bail!(
                "frame {k}: {} pixels, expected {width}x{height}",
                image.len()
            );
        }
        for y in 0..h {
            mosaic[y * n * w + k * w..][..w].copy_from_slice(&image[y * w..][..w]);
        }
    }
    // The error names the path itself.
    Ok(crate::capture::write_png(
        path,
        (n * w) as u32,
        height,
        &mosaic,
    )?)
}
