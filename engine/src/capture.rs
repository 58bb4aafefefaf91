//! Headless capture: frames to PNG (sRGB, 8-bit, for people) and EXR
//! (linear float, for measurement). Files are written atomically (temp file
//! then rename), so a failed run never leaves half an image behind.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: PNG encoding failed: {source}")]
    Png {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("{path}: EXR encoding failed: {source}")]
    Exr {
        path: PathBuf,
        source: exr::error::Error,
    },
    #[error("{path}: expected {expected} pixels ({width}x{height}), got {got}")]
    Size {
        path: PathBuf,
        width: u32,
        height: u32,
        expected: usize,
        got: usize,
    },
}

/// The sRGB transfer function of a linear value, clamped to [0, 1]. Its
/// 8-bit rounding is what PNGs hold; `util::srgb8` gives those bytes
/// from a table.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// `values` (`per_pixel` a pixel) must fill `width × height` exactly.
fn check_size(
    path: &Path,
    (width, height): (u32, u32),
    values: usize,
    per_pixel: usize,
) -> Result<(), CaptureError> {
    let expected = width as usize * height as usize;
    if values != expected * per_pixel {
        return Err(CaptureError::Size {
            path: path.into(),
            width,
            height,
            expected,
            got: values / per_pixel,
        });
    }
    Ok(())
}

/// Writes through `write(tmp)` then renames onto `path`.
fn atomically<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    wrap: impl FnOnce(E) -> CaptureError,
) -> Result<(), CaptureError> {
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{file_name}.tmp"));
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(wrap(e));
    }
    std::fs::rename(&tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        CaptureError::Io {
            path: path.into(),
            source,
        }
    })
}

/// 8-bit sRGB PNG of linear RGBA pixels (alpha dropped).
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f32; 4]],
) -> Result<(), CaptureError> {
    check_size(path, (width, height), pixels.len(), 1)?;
    write_png_rgb8(path, width, height, crate::util::srgb8::srgb8_rgb(pixels))
}

/// [`write_png`] of an RGBA16F frame as read back (4 halves a pixel): the
/// same file as for its pixels as floats.
pub fn write_png_halves(
    path: &Path,
    width: u32,
    height: u32,
    halves: &[half::f16],
) -> Result<(), CaptureError> {
    check_size(path, (width, height), halves.len(), 4)?;
    let bytes = crate::util::srgb8::srgb8_rgb_halves(halves);
    write_png_rgb8(path, width, height, bytes)
}

fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    bytes: Vec<u8>,
) -> Result<(), CaptureError> {
    let owned = path.to_path_buf();
    atomically(
        path,
        |tmp| {
            image::save_buffer_with_format(
                tmp,
                &bytes,
                width,
                height,
                image::ExtendedColorType::Rgb8,
                image::ImageFormat::Png,
            )
        },
        |source| CaptureError::Png {
            path: owned,
            source,
        },
    )
}

/// Linear float RGBA EXR.
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f32; 4]],
) -> Result<(), CaptureError> {
    check_size(path, (width, height), pixels.len(), 1)?;
    let owned = path.to_path_buf();
    atomically(
        path,
        |tmp| {
            exr::prelude::write_rgba_file(tmp, width as usize, height as usize, |x, y| {
                let p = pixels[y * width as usize + x];
                (p[0], p[1], p[2], p[3])
            })
        },
        |source| CaptureError::Exr {
            path: owned,
            source,
        },
    )
}

/// Reads an 8-bit PNG back as linear RGBA (alpha 1), for golden images.
pub fn read_png(path: &Path) -> Result<(u32, u32, Vec<[f32; 4]>), CaptureError> {
    let image = image::open(path)
        .map_err(|source| CaptureError::Png {
            path: path.into(),
            source,
        })?
        .to_rgb8();
    let pixels = image
        .pixels()
        .map(|p| {
            let [r, g, b] = p.0.map(|c| srgb_to_linear(f32::from(c) / 255.0));
            [r, g, b, 1.0]
        })
        .collect();
    Ok((image.width(), image.height(), pixels))
}

#[cfg(test)]
mod tests {
    use super::*;
    use half::f16;

    /// A frame read back as half floats writes the PNG its floats write,
    /// byte for byte; a frame of the wrong size is refused, nothing written.
    #[test]
    fn half_float_frames_write_the_same_png() {
        let dir = tempfile::tempdir().expect("tempdir");
        let values = [0.0f32, 0.002, 0.18, 0.5, 0.99, 1.0, 7.5, -0.25];
        let halves: Vec<f16> = (0..6 * 4)
            .map(|i| f16::from_f32(values[i % values.len()] * (1.0 + i as f32 / 64.0)))
            .collect();
        let floats: Vec<[f32; 4]> = halves
            .chunks_exact(4)
            .map(|p| [p[0].to_f32(), p[1].to_f32(), p[2].to_f32(), p[3].to_f32()])
            .collect();
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        write_png(&a, 3, 2, &floats).expect("floats");
        write_png_halves(&b, 3, 2, &halves).expect("halves");
        assert_eq!(std::fs::read(&a).ok(), std::fs::read(&b).ok());
        let short = dir.path().join("short.png");
        let err = write_png_halves(&short, 3, 2, &halves[..20]).expect_err("too short");
        assert!(matches!(err, CaptureError::Size { got: 5, .. }), "{err}");
        assert!(!short.exists());
    }
}
