//! Rows weighted as the screen shows their errors (`[objects.em]
//! display_weight`). The PNG a person sees is sRGB of the linear frame
//! clamped to [0, 1], so an error `e` at a pixel of linear value `y` shows
//! as about `s'(y)·e`: scaling the pixel's rows by `s'(y)` makes the least
//! squares fit display-referred errors. Linear rows let a dark rim beside a
//! bright highlight weigh 30× less than the eye sees it.

use super::Job;
use super::targets::composite_pixels;
use anyhow::Result;
use inference::trace::output;

/// Below this the slope is capped: darker pixels are mostly the traces'
/// noise, and the cap keeps any pixel within ~15× of a white one.
const FLOOR: f32 = 0.01;

/// One weight per pixel of `composite` (the object's traced appearance,
/// linear RGB): the sRGB slope at its luminance, normalized to mean 1 over
/// the pixels the object shows (luminance > 0), so the regularizers keep
/// their balance with the rows; every weight finite and > 0.
pub fn display_weights(composite: &[[f32; 4]]) -> Vec<f32> {
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let slope = |y: f32| {
        let y = if y.is_finite() {
            y.clamp(FLOOR, 1.0)
        } else {
            1.0
        };
        // d/dy (1.055 y^(1/2.4) − 0.055), up to the constant.
        y.powf(1.0 / 2.4 - 1.0)
    };
    let weights: Vec<f32> = composite.iter().map(|p| slope(luminance(p))).collect();
    // Every slope is finite and > 0, so the mean is whenever a pixel shows.
    let (sum, shown) = composite
        .iter()
        .zip(&weights)
        .filter(|(p, _)| luminance(p) > 0.0)
        .fold((0.0f64, 0usize), |(s, n), (_, &w)| {
            (s + f64::from(w), n + 1)
        });
    if shown == 0 {
        return vec![1.0; composite.len()];
    }
    let mean = sum / shown as f64;
    weights
        .iter()
        .map(|&w| (f64::from(w) / mean) as f32)
        .collect()
}

/// The display weights of a view's rows for `job` (None when its object
/// does not ask for them), from the object's traced appearance there.
pub fn view_weights(
    job: &Job,
    layers: &[output::ExrLayer],
    pixel_count: usize,
) -> Result<Option<Vec<f32>>> {
    if !job.object.display_weight() {
        return Ok(None);
    }
    let composite = composite_pixels(layers, &job.object.name, pixel_count)?;
    Ok(Some(display_weights(&composite)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dark_pixels_weigh_as_the_display_shows_them() {
        let px = |y: f32| [y, y, y, 1.0];
        let w = display_weights(&[px(1.0), px(0.04), px(0.0), px(4.0), px(0.001)]);
        // Mean 1 over the shown pixels (all but the black one).
        let shown = [w[0], w[1], w[3], w[4]];
        assert!(
            (shown.iter().sum::<f32>() / 4.0 - 1.0).abs() < 1e-5,
            "{w:?}"
        );
        // The sRGB slope: 0.04 is 0.04^(-7/12) = 6.5x white's weight.
        assert!(
            (w[1] / w[0] - 0.04f32.powf(-7.0 / 12.0)).abs() < 1e-3,
            "{w:?}"
        );
        // Clamped: above white as white, below the floor as the floor.
        assert_eq!(w[3], w[0]);
        assert!((w[4] / w[0] - FLOOR.powf(-7.0 / 12.0)).abs() < 1e-3);
        assert!(w.iter().all(|w| w.is_finite() && *w > 0.0));
    }

    #[test]
    fn nothing_shown_or_not_finite_gives_finite_weights() {
        assert_eq!(display_weights(&[[0.0; 4]; 3]), vec![1.0; 3]);
        let w = display_weights(&[[f32::NAN, 0.0, 0.0, 1.0], [0.5, 0.5, 0.5, 1.0]]);
        assert!(w.iter().all(|w| w.is_finite() && *w > 0.0), "{w:?}");
    }
}
