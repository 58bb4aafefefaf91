//! What `engine infer` writes to report.json and prints.

use inference::infer::LayerResult;
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Serialize, Deserialize)]
pub struct LayerReport {
    pub name: String,
    pub psnr_db: PsnrPair,
    pub rows: usize,
    pub nnz: usize,
    pub rows_across_cube_faces: usize,
    pub probe_renders: u32,
    pub a_vs_render_psnr_db: f64,
    pub cg_iterations: Vec<u32>,
    pub probe_s: f64,
    pub assembly_s: f64,
    pub solve_s: f64,
    pub diagnostics: Vec<String>,
}

#[derive(Serialize, Deserialize)]
pub struct PsnrPair {
    pub least_squares: f64,
    pub forward_mapping: f64,
    /// The engine-issue baseline (distant layer and sphere EM): the static
    /// EM rasterised at the EM origin, indexed as a sphere at infinity,
    /// against the same target.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_em: Option<f64>,
}

#[derive(Serialize, Deserialize)]
pub struct SampleReport {
    pub sample: u32,
    pub probe_renders: u32,
    /// The worst layer's `A x` against an actual render of random content.
    pub a_vs_render_psnr_db: f64,
    pub solve_s: f64,
    pub warm_started: bool,
    pub layers: Vec<LayerReport>,
}

impl SampleReport {
    /// The report already in `path` for sample `sample`, or a new empty
    /// one when there is none or it cannot be used (a damaged or foreign
    /// file is replaced, with a warning, not left blocking the run).
    pub(super) fn read_or_new(path: &Path, sample: u32) -> SampleReport {
        let empty = SampleReport {
            sample,
            probe_renders: 0,
            a_vs_render_psnr_db: f64::MAX,
            solve_s: 0.0,
            warm_started: false,
            layers: Vec::new(),
        };
        let Ok(bytes) = std::fs::read(path) else {
            return empty;
        };
        match serde_json::from_slice::<SampleReport>(&bytes) {
            Ok(old) if old.sample == sample => old,
            Ok(old) => {
                eprintln!(
                    "{}: reports sample {}, expected {sample}: starting it afresh",
                    path.display(),
                    old.sample
                );
                empty
            }
            Err(e) => {
                eprintln!("{}: unreadable ({e}): starting it afresh", path.display());
                empty
            }
        }
    }

    /// Sample `sample`'s report after this run inferred `fresh` layers:
    /// they replace the same-named layers of the earlier report `old` (if
    /// any), whose other layers — maps skipped as up to date, or not asked
    /// for this time — are kept. Layers follow `order` (job names; others
    /// last, as they were); the totals are recomputed over every layer, as
    /// a full run computes them.
    pub(super) fn merged(
        old: Option<SampleReport>,
        sample: u32,
        fresh: Vec<LayerReport>,
        warm_started: bool,
        order: &[String],
    ) -> SampleReport {
        let (mut layers, old_warm) =
            old.map_or((Vec::new(), false), |o| (o.layers, o.warm_started));
        // Kept layers may have been warm-started by the earlier run.
        let old_warm = old_warm
            && layers
                .iter()
                .any(|l| fresh.iter().all(|f| f.name != l.name));
        for layer in fresh {
            match layers.iter_mut().find(|l| l.name == layer.name) {
                Some(slot) => *slot = layer,
                None => layers.push(layer),
            }
        }
        let rank = |l: &LayerReport| order.iter().position(|n| *n == l.name);
        layers.sort_by_key(|l| rank(l).unwrap_or(usize::MAX));
        SampleReport {
            sample,
            // Saturating: kept layers come from JSON a user may have edited.
            probe_renders: (layers.iter()).fold(0u32, |n, l| n.saturating_add(l.probe_renders)),
            a_vs_render_psnr_db: layers
                .iter()
                .map(|l| l.a_vs_render_psnr_db)
                .fold(f64::MAX, f64::min),
            solve_s: layers.iter().map(|l| l.solve_s).sum(),
            warm_started: warm_started || old_warm,
            layers,
        }
    }
}

/// A JSON number for PSNRs, which are ∞ for exact matches.
pub(super) fn finite_or_max(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::MAX.copysign(v)
    }
}

impl From<&LayerResult> for LayerReport {
    fn from(r: &LayerResult) -> Self {
        Self {
            name: r.name.clone(),
            psnr_db: PsnrPair {
                least_squares: finite_or_max(r.psnr_least_squares_db),
                forward_mapping: finite_or_max(r.psnr_forward_db),
                static_em: None,
            },
            rows: r.rows,
            nnz: r.nnz,
            rows_across_cube_faces: r.rows_across_faces,
            probe_renders: r.probe_renders,
            a_vs_render_psnr_db: finite_or_max(r.a_vs_render_psnr_db),
            cg_iterations: r.iterations.clone(),
            probe_s: r.probe_time.as_secs_f64(),
            assembly_s: r.assembly_time.as_secs_f64(),
            solve_s: r.solve_time.as_secs_f64(),
            diagnostics: r.diagnostics.clone(),
        }
    }
}
