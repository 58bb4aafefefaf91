//! How far a rendered frame is from the traced reference: over a pixel mask
//! (the reflector's pixels), PSNR on linear RGB and NVIDIA's FLIP; over the
//! whole frame, both on what a person sees (the 8-bit sRGB PNG).
//!
//! Both take full frames, row-major from the top, linear RGBA f32 (the
//! order of `Renderer::pixels()` and of the traced layers); alpha is ignored.
//! Every result is finite or `None` (nothing to measure), so it can go into
//! JSON as is; a non-finite input value is an error naming the pixel.

use anyhow::{Result, bail};
use inference::infer::Target;
use inference::infer::layer::psnr_over_rows;

/// Bound of [`masked_psnr`] in dB: identical images score `+PSNR_CAP_DB`
/// instead of +∞, which JSON cannot hold. 100 dB is an RMS error of 10⁻⁵ of
/// the peak, far below the f16 framebuffer's resolution (≈ 5·10⁻⁴ relative),
/// so no real comparison reaches it.
pub const PSNR_CAP_DB: f64 = 100.0;

/// FLIP's default observer: 67 pixels per degree, a 0.7 m wide 4K monitor
/// seen from 0.7 m (FLIP paper §3; `nv_flip::DEFAULT_PIXELS_PER_DEGREE`).
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// Both scores of one frame against its reference over one mask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scores {
    /// [`masked_psnr`]; `None` when the mask is empty.
    pub psnr_db: Option<f64>,
    /// [`masked_flip`]; `None` when the mask is empty.
    pub flip: Option<f64>,
    /// Pixels in the mask.
    pub pixels: usize,
}

/// PSNR in dB of `test` against `reference` over the pixels where `mask` is
/// true, on linear R, G, B.
///
/// The definition is `inference::infer::layer::psnr_over_rows`, which this
/// calls: MSE over the masked pixels' R, G and B samples, and **peak = the
/// reference's largest absolute sample there** (HDR-safe: a highlight of 6
/// sets the peak to 6, not 1; the peak depends on the reference only, so
/// every mode is scored against the same peak at a given view). So
/// `10·log10(peak² / MSE)`, bounded to `±PSNR_CAP_DB`: identical pixels give
/// `+PSNR_CAP_DB`, and a reference that is black over the whole mask against a
/// test that is not (no peak to measure against) gives `−PSNR_CAP_DB`.
///
/// `None` when the mask selects no pixel. An error when the three lengths
/// differ or a masked value is not finite.
pub fn masked_psnr(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    mask: &[bool],
) -> Result<Option<f64>> {
    check_lengths(reference.len(), test.len(), mask.len())?;
    let rows: Vec<u32> = masked_indices(mask)?;
    if rows.is_empty() {
        return Ok(None);
    }
    for &p in &rows {
        check_finite("reference", reference, p as usize)?;
        check_finite("test", test, p as usize)?;
    }
    let target = Target {
        name: "reference",
        pixels: reference,
        channels: 3,
    };
    let db = psnr_over_rows(test, &target, &rows);
    // ±∞ are the two cases the doc names; the finite samples exclude NaN.
    Ok(Some(db.clamp(-PSNR_CAP_DB, PSNR_CAP_DB)))
}

/// Mean FLIP error over the masked pixels: 0 for identical, up to 1.
///
/// LDR-FLIP (the `nv-flip` crate, NVIDIA's reference C++ code): both frames
/// are clamped to [0, 1], sRGB-encoded and quantised to 8 bits — as the
/// engine writes PNGs — then compared at [`FLIP_PIXELS_PER_DEGREE`]. Values
/// above 1 (the light, bright highlights) compare as 1: HDR-FLIP is not
/// available in that crate. The error map is computed on the full frames and
/// averaged over the mask, so a masked pixel's error also sees its
/// neighbourhood (FLIP filters spatially), as a viewer would.
///
/// `None` when the mask selects no pixel. An error when the lengths do not
/// match `width × height` or a value is not finite.
pub fn masked_flip(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    width: u32,
    height: u32,
    mask: &[bool],
) -> Result<Option<f64>> {
    check_lengths(reference.len(), test.len(), mask.len())?;
    if !mask.iter().any(|&m| m) {
        return Ok(None);
    }
    let map = flip_error_map(reference, test, width, height)?;
    let (sum, n) = map
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0f64, 0usize), |(s, n), (e, _)| {
            (s + f64::from(*e), n + 1)
        });
    Ok(Some(sum / n as f64))
}

/// FLIP's per-pixel error map (row-major from the top, each in [0, 1]) of
/// `test` against `reference`, both converted as [`masked_flip`] says.
pub fn flip_error_map(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    width: u32,
    height: u32,
) -> Result<Vec<f32>> {
    let expected = width as usize * height as usize;
    if width == 0 || height == 0 {
        bail!("FLIP: expected a frame of at least 1x1 pixels, got {width}x{height}");
    }
    for (what, image) in [("reference", reference), ("test", test)] {
        if image.len() != expected {
            bail!(
                "FLIP: the {what} frame has {} pixels, expected {expected} ({width}x{height})",
                image.len()
            );
        }
        for p in 0..image.len() {
            check_finite(what, image, p)?;
        }
    }
    let flip_image = |image: &[[f32; 4]]| {
        nv_flip::FlipImageRgb8::with_data(width, height, &display_bytes(image))
    };
    let map = nv_flip::flip(
        flip_image(reference),
        flip_image(test),
        FLIP_PIXELS_PER_DEGREE,
    );
    Ok(map
        .to_vec()
        .into_iter()
        .map(|e| {
            if e.is_finite() {
                e.clamp(0.0, 1.0)
            } else {
                1.0
            }
        })
        .collect())
}

/// The frame as the engine writes it to PNG: each linear value clamped to
/// [0, 1], sRGB-encoded and rounded to 8 bits (`capture::write_png`), RGB.
pub fn display_bytes(image: &[[f32; 4]]) -> Vec<u8> {
    crate::util::srgb8::srgb8_rgb(image)
}

/// |display(a) − display(b)| × `gain`, the largest channel, as a grey
/// linear frame whose PNG shows that value: the error as the display
/// metrics weigh it, for pictures.
pub fn display_difference(a: &[[f32; 4]], b: &[[f32; 4]], gain: f32) -> Vec<[f32; 4]> {
    let (a, b) = (display_bytes(a), display_bytes(b));
    a.chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(p, q)| {
            let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0);
            let v = crate::capture::srgb_to_linear((f32::from(d) / 255.0 * gain).min(1.0));
            [v, v, v, 1.0]
        })
        .collect()
}

/// Display-referred PSNR in dB over every pixel: both frames through
/// [`display_bytes`] (what a person sees in the PNG), peak 255, MSE over
/// R, G and B of all pixels; bounded to `PSNR_CAP_DB` for identical frames.
/// Unlike [`masked_psnr`] (linear, peak = the reference's maximum, which the
/// light sets at ~12 and so hides the room's errors) this weighs an error as
/// visibly as the screen shows it.
pub fn display_psnr(reference: &[[f32; 4]], test: &[[f32; 4]]) -> Result<f64> {
    check_lengths(reference.len(), test.len(), test.len())?;
    if reference.is_empty() {
        bail!("display PSNR: expected a frame of at least one pixel");
    }
    for p in 0..reference.len() {
        check_finite("reference", reference, p)?;
        check_finite("test", test, p)?;
    }
    let (a, b) = (display_bytes(reference), display_bytes(test));
    let sum: f64 = a
        .iter()
        .zip(&b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum();
    let mse = sum / a.len() as f64;
    Ok(if mse == 0.0 {
        PSNR_CAP_DB
    } else {
        (10.0 * (255.0f64 * 255.0 / mse).log10()).min(PSNR_CAP_DB)
    })
}

/// [`display_psnr`] over the pixels where `mask` is set, and their share
/// of the whole frame's squared error (0 to 1); None when the mask is empty.
/// Splits a frame's error by object (the traced `<object>.mask` layers).
pub fn display_psnr_masked(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    mask: &[bool],
) -> Result<Option<(f64, f64)>> {
    check_lengths(reference.len(), test.len(), mask.len())?;
    let (a, b) = (display_bytes(reference), display_bytes(test));
    let sq = |p: usize| -> f64 {
        (0..3)
            .map(|c| (f64::from(a[3 * p + c]) - f64::from(b[3 * p + c])).powi(2))
            .sum()
    };
    let total: f64 = (0..reference.len()).map(sq).sum();
    let pixels: Vec<usize> = (0..mask.len()).filter(|&p| mask[p]).collect();
    if pixels.is_empty() {
        return Ok(None);
    }
    let sum: f64 = pixels.iter().map(|&p| sq(p)).sum();
    let mse = sum / (3 * pixels.len()) as f64;
    let psnr = if mse == 0.0 {
        PSNR_CAP_DB
    } else {
        (10.0 * (255.0f64 * 255.0 / mse).log10()).min(PSNR_CAP_DB)
    };
    Ok(Some((psnr, if total > 0.0 { sum / total } else { 0.0 })))
}

/// Whole-frame scores of one frame: [`display_psnr`] and the mean FLIP
/// ([`flip_error_map`]) over every pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameScores {
    pub psnr_db: f64,
    pub flip: f64,
}

/// [`FrameScores`] of `test` against `reference` (`width × height` each).
pub fn frame_scores(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    width: u32,
    height: u32,
) -> Result<FrameScores> {
    let map = flip_error_map(reference, test, width, height)?;
    let flip = map.iter().map(|&e| f64::from(e)).sum::<f64>() / map.len() as f64;
    Ok(FrameScores {
        psnr_db: display_psnr(reference, test)?,
        flip,
    })
}

/// [`masked_psnr`] and [`masked_flip`] of one frame.
pub fn scores(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    width: u32,
    height: u32,
    mask: &[bool],
) -> Result<Scores> {
    Ok(Scores {
        psnr_db: masked_psnr(reference, test, mask)?,
        flip: masked_flip(reference, test, width, height, mask)?,
        pixels: mask.iter().filter(|&&m| m).count(),
    })
}

fn check_lengths(reference: usize, test: usize, mask: usize) -> Result<()> {
    if reference != test || reference != mask {
        bail!(
            "expected a reference, a test frame and a mask of the same size, got {reference}, {test} and {mask} pixels"
        );
    }
    Ok(())
}

fn masked_indices(mask: &[bool]) -> Result<Vec<u32>> {
    mask.iter()
        .enumerate()
        .filter(|(_, m)| **m)
        .map(|(i, _)| {
            u32::try_from(i).map_err(|_| anyhow::anyhow!("frame too large: pixel index {i}"))
        })
        .collect()
}

fn check_finite(what: &str, image: &[[f32; 4]], p: usize) -> Result<()> {
    if let Some(c) = image[p][..3].iter().position(|v| !v.is_finite()) {
        bail!(
            "{what} frame: pixel {p} channel {c} is {}, expected a finite value",
            image[p][c]
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: u32 = 64;
    const H: u32 = 32;

    /// A smooth gradient with values in [0.05, 0.85].
    fn gradient() -> Vec<[f32; 4]> {
        (0..W * H)
            .map(|i| {
                let (x, y) = ((i % W) as f32 / W as f32, (i / W) as f32 / H as f32);
                [0.05 + 0.8 * x, 0.05 + 0.4 * y, 0.3, 1.0]
            })
            .collect()
    }

    fn all(on: bool) -> Vec<bool> {
        vec![on; (W * H) as usize]
    }

    #[test]
    fn identical_frames_score_best() -> Result<()> {
        let a = gradient();
        let s = scores(&a, &a, W, H, &all(true))?;
        assert_eq!(s.psnr_db, Some(PSNR_CAP_DB));
        assert_eq!(s.flip, Some(0.0));
        assert_eq!(s.pixels, (W * H) as usize);
        Ok(())
    }

    #[test]
    fn known_perturbation_gives_the_closed_form_psnr() -> Result<()> {
        let reference = gradient();
        let mask: Vec<bool> = (0..W * H).map(|i| i % 3 == 0).collect();
        // +0.01 on green of every masked pixel, and garbage elsewhere.
        let test: Vec<[f32; 4]> = reference
            .iter()
            .zip(&mask)
            .map(|(p, &m)| {
                if m {
                    [p[0], p[1] + 0.01, p[2], 0.0]
                } else {
                    [9.0, -9.0, 9.0, 1.0]
                }
            })
            .collect();
        let peak = reference
            .iter()
            .zip(&mask)
            .filter(|(_, m)| **m)
            .flat_map(|(p, _)| p[..3].to_vec())
            .fold(0.0f32, f32::max);
        // Squared error as f64 of the f32 difference, one channel in three.
        let d = reference
            .iter()
            .zip(&test)
            .zip(&mask)
            .filter(|(_, m)| **m)
            .map(|((r, t), _)| (f64::from(t[1]) - f64::from(r[1])).powi(2))
            .sum::<f64>();
        let n = 3.0 * mask.iter().filter(|&&m| m).count() as f64;
        let expected = 10.0 * (f64::from(peak).powi(2) / (d / n)).log10();
        let got = masked_psnr(&reference, &test, &mask)?;
        assert!(
            got.is_some_and(|g| (g - expected).abs() < 1e-6),
            "{got:?} vs {expected}"
        );
        // Sanity of the closed form itself: RMS 0.01/√3 against the peak.
        let approx = 10.0 * (f64::from(peak).powi(2) / (1e-4 / 3.0)).log10();
        assert!((expected - approx).abs() < 1e-3);
        Ok(())
    }

    #[test]
    fn only_masked_pixels_count() -> Result<()> {
        let reference = gradient();
        // Left half wildly wrong; the mask is the rightmost quarter, 16 px away.
        let test: Vec<[f32; 4]> = reference
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if (i as u32 % W) < W / 2 {
                    [1.0, 0.0, 1.0, 1.0]
                } else {
                    *p
                }
            })
            .collect();
        let right: Vec<bool> = (0..W * H).map(|i| i % W >= 3 * W / 4).collect();
        let s = scores(&reference, &test, W, H, &right)?;
        assert_eq!(s.psnr_db, Some(PSNR_CAP_DB));
        assert!(s.flip.is_some_and(|f| f < 1e-6), "{:?}", s.flip);
        let left: Vec<bool> = right.iter().map(|m| !m).collect();
        let s = scores(&reference, &test, W, H, &left)?;
        assert!(s.psnr_db.is_some_and(|p| p < 20.0), "{:?}", s.psnr_db);
        assert!(s.flip.is_some_and(|f| f > 0.1), "{:?}", s.flip);
        Ok(())
    }

    #[test]
    fn black_frames_are_finite() -> Result<()> {
        let black = vec![[0.0, 0.0, 0.0, 1.0]; (W * H) as usize];
        let s = scores(&black, &black, W, H, &all(true))?;
        assert_eq!(s.psnr_db, Some(PSNR_CAP_DB));
        assert_eq!(s.flip, Some(0.0));
        // Nothing to measure against: the worst bound, not −∞ or NaN.
        let grey = vec![[0.5, 0.5, 0.5, 1.0]; (W * H) as usize];
        let s = scores(&black, &grey, W, H, &all(true))?;
        assert_eq!(s.psnr_db, Some(-PSNR_CAP_DB));
        assert!(s.flip.is_some_and(|f| f.is_finite() && f > 0.0));
        // And the other way round: a finite PSNR below 0 dB is not clamped.
        let s = scores(&grey, &black, W, H, &all(true))?;
        assert!(s.psnr_db.is_some_and(|p| p.abs() < 1e-9), "{:?}", s.psnr_db);
        Ok(())
    }

    #[test]
    fn an_empty_mask_measures_nothing() -> Result<()> {
        let a = gradient();
        let s = scores(&a, &a, W, H, &all(false))?;
        assert_eq!((s.psnr_db, s.flip, s.pixels), (None, None, 0));
        Ok(())
    }

    #[test]
    fn whole_frame_scores_are_display_referred() -> Result<()> {
        let reference = gradient();
        let same = frame_scores(&reference, &reference, W, H)?;
        assert_eq!(
            same,
            FrameScores {
                psnr_db: PSNR_CAP_DB,
                flip: 0.0
            }
        );
        // One 8-bit step on red of every pixel: MSE = 1/3, so the closed
        // form 10·log10(255² · 3) whatever the pixel's brightness.
        let step: Vec<[f32; 4]> = display_bytes(&reference)
            .chunks_exact(3)
            .map(|c| {
                let v = |k: usize| crate::capture::srgb_to_linear(f32::from(c[k]) / 255.0);
                let r = crate::capture::srgb_to_linear((f32::from(c[0]) + 1.0) / 255.0);
                [r, v(1), v(2), 1.0]
            })
            .collect();
        let got = display_psnr(&reference, &step)?;
        let expected = 10.0 * (255.0f64 * 255.0 * 3.0).log10();
        assert!((got - expected).abs() < 1e-9, "{got} vs {expected}");
        // Values above 1 (the light) clip as on screen: no error there.
        let bright: Vec<[f32; 4]> = vec![[12.0, 11.0, 10.0, 1.0]; reference.len()];
        let brighter: Vec<[f32; 4]> = vec![[20.0, 20.0, 20.0, 1.0]; reference.len()];
        assert_eq!(display_psnr(&bright, &brighter)?, PSNR_CAP_DB);
        // Dark pixels 1.5× too bright: 7 to 14 sRGB levels, visible, and
        // scored so although their linear error is under 0.05.
        let dim: Vec<[f32; 4]> = reference.iter().map(|p| p.map(|c| 0.1 * c)).collect();
        let dim_bright: Vec<[f32; 4]> = dim.iter().map(|p| p.map(|c| 1.5 * c)).collect();
        let s = frame_scores(&dim, &dim_bright, W, H)?;
        assert!(s.psnr_db < 32.0 && s.flip > 0.01, "{s:?}");
        assert!(display_psnr(&reference, &reference[1..]).is_err());
        // Split by a mask: the masked half holds all of the error.
        let mut half = reference.clone();
        let mask: Vec<bool> = (0..half.len()).map(|p| p % 2 == 0).collect();
        for (p, v) in half.iter_mut().enumerate() {
            if mask[p] {
                *v = v.map(|c| 0.5 * c);
            }
        }
        let (db, share) = display_psnr_masked(&reference, &half, &mask)?.expect("pixels");
        assert_eq!(share, 1.0);
        assert!(db < display_psnr(&reference, &half)?);
        let none = vec![false; half.len()];
        assert_eq!(display_psnr_masked(&reference, &half, &none)?, None);
        Ok(())
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let a = gradient();
        let short = &a[1..];
        assert!(masked_psnr(&a, short, &all(true)).is_err());
        assert!(masked_flip(&a, &a, W + 1, H, &all(true)).is_err());
        assert!(flip_error_map(&[], &[], 0, 0).is_err());
        let mut nan = a.clone();
        nan[5][1] = f32::NAN;
        let e = masked_psnr(&a, &nan, &all(true))
            .err()
            .map(|e| e.to_string());
        assert!(
            e.as_ref().is_some_and(|e| e.contains("pixel 5 channel 1")),
            "{e:?}"
        );
        let mut inf = a.clone();
        inf[7][0] = f32::INFINITY;
        assert!(masked_flip(&a, &inf, W, H, &all(true)).is_err());
    }
}
