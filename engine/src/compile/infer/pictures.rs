//! Pictures `engine infer` writes for people: the renders side by side, and
//! the inferred map itself with its MIP levels.

use crate::capture::write_png;
use anyhow::Result;
use inference::infer::LayerResult;
use inference::solve::layout::TextureLayout;
use std::path::Path;

/// target | least squares | forward mapping, cropped to the object's
/// bounding box (RGB, premultiplied for RGBA layers), sRGB PNG.
pub(super) fn write_comparison(
    path: &Path,
    width: u32,
    target: &[[f32; 4]],
    r: &LayerResult,
) -> Result<()> {
    let (Some(x0), Some(x1)) = (
        r.pixels.iter().map(|p| p % width).min(),
        r.pixels.iter().map(|p| p % width).max(),
    ) else {
        return Ok(()); // nothing visible, nothing to show
    };
    let (y0, y1) = (r.pixels[0] / width, r.pixels[r.pixels.len() - 1] / width);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let gap = 4;
    let total = 3 * w + 2 * gap;
    let mut out = vec![[0.0f32; 4]; (total * h) as usize];
    let object: std::collections::HashSet<u32> = r.pixels.iter().copied().collect();
    for (panel, image) in [target, &r.rendered_least_squares, &r.rendered_forward]
        .into_iter()
        .enumerate()
    {
        for y in 0..h {
            for x in 0..w {
                let p = (y0 + y) * width + x0 + x;
                if object.contains(&p) {
                    out[(y * total + panel as u32 * (w + gap) + x) as usize] = image[p as usize];
                }
            }
        }
    }
    crate::capture::write_png(path, total, h, &out)?;
    Ok(())
}

/// The map's faces side by side (Vulkan order +X, −X, +Y, −Y, +Z, −Z), each
/// MIP level below the previous at its own size, RGB (premultiplied for
/// RGBA layers), sRGB PNG.
pub(super) fn write_map_picture(
    path: &Path,
    layout: &TextureLayout,
    map: &[Vec<f32>],
) -> Result<()> {
    let faces = layout.faces();
    let (w0, _) = layout.level_size(0);
    let gap = 2;
    let width = faces * (w0 + gap);
    let height: u32 = (0..layout.levels())
        .map(|l| layout.level_size(l).1 + gap)
        .sum();
    let mut out = vec![[0.0f32; 4]; (width * height) as usize];
    let mut top = 0;
    for level in 0..layout.levels() {
        let (w, h) = layout.level_size(level);
        for face in 0..faces {
            for y in 0..h {
                for x in 0..w {
                    let i = layout.index(face, level, x, y);
                    let c = |k: usize| map.get(k).map_or(0.0, |m| m[i]);
                    out[((top + y) * width + face * (w0 + gap) + x) as usize] =
                        [c(0), c(1), c(2), 1.0];
                }
            }
        }
        top += h + gap;
    }
    write_png(path, width, height, &out)?;
    Ok(())
}
