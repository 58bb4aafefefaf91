//! Re-draws the ratio-against-PSNR chart of an `engine codec-report
//! --curve` JSON without re-measuring (the report draws it itself too).
//!
//! `cargo run --release -p engine --example plot_codec_curves -- REPORT.json OUT.png`

use anyhow::{Context, Result, bail};
use codec::report::{Curve, CurvePoint};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [json, png] = args.as_slice() else {
        bail!("usage: plot_codec_curves REPORT.json OUT.png");
    };
    let text = std::fs::read(json).with_context(|| format!("reading {json}"))?;
    let report: serde_json::Value =
        serde_json::from_slice(&text).with_context(|| format!("{json}: not JSON"))?;
    let Some(list) = report["curves"].as_array() else {
        bail!("{json}: no \"curves\" array (run codec-report with --curve)");
    };
    let mut curves = Vec::new();
    for c in list {
        let metric: &'static str = match c["metric"].as_str() {
            Some("texture") => "texture",
            Some("frames_vs_traced") => "frames_vs_traced",
            Some("frames_vs_uncompressed") => "frames_vs_uncompressed",
            other => bail!("{json}: curve metric {other:?} (expected texture or frames_vs_*)"),
        };
        let mut curve = Curve::new(c["name"].as_str().unwrap_or("?"), metric);
        for p in c["points"].as_array().into_iter().flatten() {
            let (Some(ratio), Some(psnr_db)) = (p["ratio"].as_f64(), p["psnr_db"].as_f64()) else {
                bail!("{json}: a curve point without ratio and psnr_db: {p}");
            };
            curve.points.push(CurvePoint {
                ratio,
                psnr_db,
                bytes: p["bytes"].as_u64().unwrap_or(0),
            });
        }
        curves.push(curve);
    }
    engine::codec_report::plot_curves(std::path::Path::new(png), &curves)
}
