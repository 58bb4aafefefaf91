//! What `engine infer` writes to report.json and prints.

use inference::infer::LayerResult;
use serde::Serialize;

#[derive(Serialize)]
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

#[derive(Serialize)]
pub struct PsnrPair {
    pub least_squares: f64,
    pub forward_mapping: f64,
    /// The engine-issue baseline (distant layers): the static EM rasterised
    /// at the EM origin, indexed as a sphere at infinity.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_em: Option<f64>,
}

#[derive(Serialize)]
pub struct SampleReport {
    pub sample: u32,
    pub probe_renders: u32,
    /// The worst layer's `A x` against an actual render of random content.
    pub a_vs_render_psnr_db: f64,
    pub solve_s: f64,
    pub warm_started: bool,
    pub layers: Vec<LayerReport>,
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
