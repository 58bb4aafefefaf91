//! Medians over every sample inferred so far (all `sample_*/report.json` in
//! the output folder, skipped samples included), per layer.

use crate::util::stats::median;
use anyhow::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Serialize, Default)]
pub(super) struct LayerSummary {
    pub samples: usize,
    pub least_squares_db_median: f64,
    pub forward_mapping_db_median: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_em_db_median: Option<f64>,
    /// Samples where least squares beat forward mapping by ≥ 2.4 dB.
    pub samples_gain_at_least_2_4_db: usize,
    pub solve_s_median: f64,
    pub probe_s_median: f64,
}

/// Reads the sample reports under `dir`, writes `dir/summary.json` and
/// returns the printed table (empty when there is at most one sample).
pub(super) fn summarize(dir: &Path) -> Result<String> {
    let mut columns: BTreeMap<String, Vec<serde_json::Value>> = BTreeMap::new();
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.filter_map(Result::ok).collect();
    entries.sort_by_key(|e| e.file_name());
    for entry in entries {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !name.starts_with("sample_") {
            continue;
        }
        let Ok(bytes) = std::fs::read(entry.path().join("report.json")) else {
            continue;
        };
        let Ok(report) = serde_json::from_slice::<serde_json::Value>(&bytes) else {
            continue;
        };
        for layer in report["layers"].as_array().into_iter().flatten() {
            if let Some(n) = layer["name"].as_str() {
                columns
                    .entry(n.to_string())
                    .or_default()
                    .push(layer.clone());
            }
        }
    }
    let mut summary = BTreeMap::new();
    let mut text = String::new();
    for (name, layers) in &columns {
        let values = |f: &dyn Fn(&serde_json::Value) -> Option<f64>| -> Vec<f64> {
            layers.iter().filter_map(f).collect()
        };
        let ls = values(&|l| l["psnr_db"]["least_squares"].as_f64());
        let fm = values(&|l| l["psnr_db"]["forward_mapping"].as_f64());
        let st = values(&|l| l["psnr_db"]["static_em"].as_f64());
        let s = LayerSummary {
            samples: layers.len(),
            least_squares_db_median: median(&ls),
            forward_mapping_db_median: median(&fm),
            static_em_db_median: (!st.is_empty()).then(|| median(&st)),
            samples_gain_at_least_2_4_db: ls
                .iter()
                .zip(&fm)
                .filter(|(a, b)| **a >= **b + 2.4)
                .count(),
            solve_s_median: median(&values(&|l| l["solve_s"].as_f64())),
            probe_s_median: median(&values(&|l| l["probe_s"].as_f64())),
        };
        text += &format!(
            "{name:<26} {} samples: LS {:.2} dB, forward {:.2} dB{} (medians); LS ≥ forward + 2.4 dB in {} samples; solve {:.2} s, probes {:.1} s (medians)\n",
            s.samples,
            s.least_squares_db_median,
            s.forward_mapping_db_median,
            s.static_em_db_median
                .map_or(String::new(), |v| format!(", static EM {v:.2} dB")),
            s.samples_gain_at_least_2_4_db,
            s.solve_s_median,
            s.probe_s_median
        );
        summary.insert(name.clone(), s);
    }
    crate::util::files::write_json(&dir.join("summary.json"), &summary)?;
    let samples = summary.values().map(|s| s.samples).max().unwrap_or(0);
    Ok(if samples > 1 { text } else { String::new() })
}
