//! The speed/accuracy chart of `engine eval`.

use super::plot::{ChartSpec, LegendPosition, Series, xy_chart};
use super::table::{EvalRow, EvalTable};
use anyhow::Result;
use std::path::Path;

/// PSNR between samples and above the plane against frame time, one point
/// per row (the traced row is off the time scale and left out).
pub fn tradeoff_chart(path: &Path, table: &EvalTable, title: &str) -> Result<()> {
    let rows: Vec<&EvalRow> = table.rows.iter().filter(|r| r.mode != "trace").collect();
    let label = |r: &EvalRow| {
        r.settings
            .get("label")
            .and_then(|v| v.as_str())
            .unwrap_or(&r.mode)
            .to_string()
    };
    let mut spec = ChartSpec::new(
        title,
        "frame time (ms, median, maps resident)",
        "PSNR against the tracer over the reflector (dB)",
    );
    spec.legend = LegendPosition::LowerRight;
    for (name, f, labelled) in [
        (
            "between samples",
            (|r: &EvalRow| r.psnr_between_db) as fn(&EvalRow) -> f64,
            true,
        ),
        ("above the plane", |r: &EvalRow| r.psnr_above_db, false),
    ] {
        spec.series.push(Series {
            name: name.into(),
            points: rows.iter().map(|r| (r.frame_ms, f(r))).collect(),
            labels: if labelled {
                rows.iter().map(|r| label(r)).collect()
            } else {
                Vec::new()
            },
            connect: false,
        });
    }
    xy_chart(path, &spec)
}
