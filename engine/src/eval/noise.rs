//! What the references' own noise costs each row. The
//! [`REFERENCE_NOISE`](super::rows::REFERENCE_NOISE) row traces every view
//! again with another seed: two independent traces differ by twice one's
//! noise variance, so a row's mean squared error less half that row's is
//! what the row would score against a converged tracer.

use super::rows::REFERENCE_NOISE;
use super::table::EvalRow;
use serde::{Deserialize, Serialize};

/// A row's PSNRs with the references' noise taken out, each `None` where
/// the row's error is within that noise (or the score is missing).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseFree {
    pub psnr_on_db: Option<f64>,
    pub psnr_between_db: Option<f64>,
    pub psnr_above_db: Option<f64>,
    pub psnr_frame_on_db: Option<f64>,
    pub psnr_frame_between_db: Option<f64>,
    pub psnr_frame_above_db: Option<f64>,
}

/// `row_db` (PSNR against the references) with their noise taken out,
/// given `noise_db`, an independent retrace's PSNR against them (same
/// peak): `MSE_row − MSE_noise / 2`.
pub fn without_noise(row_db: f64, noise_db: f64) -> Option<f64> {
    if !(row_db.is_finite() && noise_db.is_finite()) {
        return None;
    }
    let mse = 10f64.powf(-row_db / 10.0) - 0.5 * 10f64.powf(-noise_db / 10.0);
    (mse > 0.0).then(|| -10.0 * mse.log10())
}

fn label(row: &EvalRow) -> &str {
    row.settings
        .get("label")
        .and_then(|v| v.as_str())
        .unwrap_or("")
}

/// Sets every other row's `noise_free` from the noise row, when the table
/// has one (from the dB means of each kind of view).
pub fn attach(rows: &mut [EvalRow]) {
    let Some(noise) = rows.iter().find(|r| label(r) == REFERENCE_NOISE).cloned() else {
        return;
    };
    for row in rows.iter_mut().filter(|r| label(r) != REFERENCE_NOISE) {
        let free = |f: fn(&EvalRow) -> Option<f64>| {
            f(row).zip(f(&noise)).and_then(|(r, n)| without_noise(r, n))
        };
        row.noise_free = Some(NoiseFree {
            psnr_on_db: free(|r| Some(r.psnr_on_db)),
            psnr_between_db: free(|r| Some(r.psnr_between_db)),
            psnr_above_db: free(|r| Some(r.psnr_above_db)),
            psnr_frame_on_db: free(|r| r.psnr_frame_on_db),
            psnr_frame_between_db: free(|r| r.psnr_frame_between_db),
            psnr_frame_above_db: free(|r| r.psnr_frame_above_db),
        });
    }
}

/// One line per row that has them: its scores with the references' noise
/// taken out.
pub fn markdown(rows: &[EvalRow]) -> String {
    let cell = |v: Option<f64>| v.map_or("—".to_owned(), |v| format!("{v:.2}"));
    let mut out = String::new();
    for row in rows {
        let Some(n) = &row.noise_free else {
            continue;
        };
        if out.is_empty() {
            out += "\nWith the references' noise taken out (the `trace reference-noise` row), \
                    on / between / above, dB:\n";
        }
        out += &format!(
            "- {}: reflector {} / {} / {}, frame {} / {} / {}\n",
            label(row),
            cell(n.psnr_on_db),
            cell(n.psnr_between_db),
            cell(n.psnr_above_db),
            cell(n.psnr_frame_on_db),
            cell(n.psnr_frame_between_db),
            cell(n.psnr_frame_above_db)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_the_retrace_error_is_taken_out() {
        // Scoring as the retrace does: the row's error is the noise alone
        // once, so without it the row is 3 dB better.
        let db = without_noise(37.0, 37.0).expect("some");
        assert!((db - (37.0 + 10.0 * 2f64.log10())).abs() < 1e-9, "{db}");
        // Far above the noise, the row barely moves.
        let far = without_noise(30.0, 50.0).expect("some");
        assert!(far > 30.0 && far < 30.03, "{far}");
        // A row better than a perfect frame's expectation is within the
        // noise: nothing to say.
        assert_eq!(without_noise(41.0, 37.0), None);
        assert_eq!(without_noise(f64::NAN, 37.0), None);
    }
}
