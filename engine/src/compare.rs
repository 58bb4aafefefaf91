//! Image comparison for regression tests and quality reports.

/// PSNR in dB of `test` against `reference` over RGB, with the peak taken
/// as 1.0 (display-referred). Infinite for identical images.
pub fn psnr(reference: &[[f32; 4]], test: &[[f32; 4]]) -> f64 {
    let n = reference.len().min(test.len());
    if n == 0 {
        return f64::NAN;
    }
    let sum: f64 = reference
        .iter()
        .zip(test)
        .flat_map(|(a, b)| (0..3).map(move |c| f64::from(a[c] - b[c]).powi(2)))
        .sum();
    let mse = sum / (3 * n) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}

/// Largest absolute per-channel difference over RGB.
pub fn max_abs_error(reference: &[[f32; 4]], test: &[[f32; 4]]) -> f32 {
    reference
        .iter()
        .zip(test)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0, f32::max)
}

/// A visual diff: |a − b| scaled by `gain`, for writing next to a failure.
pub fn diff_image(reference: &[[f32; 4]], test: &[[f32; 4]], gain: f32) -> Vec<[f32; 4]> {
    reference
        .iter()
        .zip(test)
        .map(|(a, b)| {
            let d = |c: usize| ((a[c] - b[c]).abs() * gain).min(1.0);
            [d(0), d(1), d(2), 1.0]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_of_known_error() {
        let a = vec![[0.5, 0.5, 0.5, 1.0]; 16];
        let b = vec![[0.6, 0.5, 0.4, 1.0]; 16];
        // MSE = (0.01 + 0 + 0.01) / 3
        let expected = 10.0 * (3.0f64 / 0.02).log10();
        assert!((psnr(&a, &b) - expected).abs() < 1e-3);
        assert_eq!(psnr(&a, &a), f64::INFINITY);
        assert!((max_abs_error(&a, &b) - 0.1).abs() < 1e-6);
    }
}
