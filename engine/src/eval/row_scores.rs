//! One eval row's line of the table: each kind of view's mean scores and
//! the frame times ([`table_row`]), then what the row played — its maps'
//! bytes, samples, shell layers and compile minutes ([`with_facts`]).

use super::rows::Row;
use super::run::ViewResult;
use super::table::{AboveScore, EvalRow, ViewCounts};
use super::views::Category;
use crate::options::Mode;
use crate::renderer::Renderer;
use crate::util::stats::{mean, median, percentile};
use inference::scene::Scene;

/// A row of the table: each kind of view's mean scores, the frame times.
pub(super) fn table_row(row: &Row, results: &[ViewResult], views: u32) -> EvalRow {
    // The mean of `f` over the views `keep` accepts.
    let mean_of = |keep: &dyn Fn(&ViewResult) -> bool, f: fn(&ViewResult) -> f64| {
        mean(
            &results
                .iter()
                .filter(|r| keep(r))
                .map(f)
                .collect::<Vec<_>>(),
        )
    };
    let kind = |c: Category, f| mean_of(&|r| r.category == c, f);
    let times: Vec<f64> = results.iter().map(|r| r.frame_ms).collect();
    let mut elevations: Vec<f32> = results
        .iter()
        .filter(|r| r.category == Category::Above)
        .map(|r| r.elevation_deg)
        .collect();
    elevations.dedup();
    let at = |e: f32, f| {
        mean_of(
            &|r| r.category == Category::Above && r.elevation_deg == e,
            f,
        )
    };
    let above: Vec<AboveScore> = elevations
        .iter()
        .map(|&e| AboveScore {
            elevation_deg: e,
            psnr_db: at(e, |r| r.psnr_db),
            flip: at(e, |r| r.flip),
            psnr_frame_db: Some(at(e, |r| r.frame.psnr_db)),
            flip_frame: Some(at(e, |r| r.frame.flip)),
        })
        .collect();
    let first = |f: fn(&AboveScore) -> f64| above.first().map_or(f64::NAN, f);
    // Whole-frame scores above the plane: the first elevation, as *_above.
    let frame_above = |f: fn(&ViewResult) -> f64| elevations.first().map(|&e| at(e, f));
    EvalRow {
        mode: row
            .label
            .split(' ')
            .next()
            .unwrap_or(&row.label)
            .to_string(),
        settings: row.settings(),
        psnr_on_db: kind(Category::On, |r| r.psnr_db),
        psnr_between_db: kind(Category::Between, |r| r.psnr_db),
        psnr_above_db: first(|a| a.psnr_db),
        flip_on: kind(Category::On, |r| r.flip),
        flip_between: kind(Category::Between, |r| r.flip),
        flip_above: first(|a| a.flip),
        psnr_frame_on_db: Some(kind(Category::On, |r| r.frame.psnr_db)),
        psnr_frame_between_db: Some(kind(Category::Between, |r| r.frame.psnr_db)),
        psnr_frame_above_db: frame_above(|r| r.frame.psnr_db),
        flip_frame_on: Some(kind(Category::On, |r| r.frame.flip)),
        flip_frame_between: Some(kind(Category::Between, |r| r.frame.flip)),
        flip_frame_above: frame_above(|r| r.frame.flip),
        frame_ms: median(&times),
        frame_ms_p95: Some(percentile(&times, 0.95)),
        views: Some(ViewCounts {
            on: views,
            between: views,
            above: views,
        }),
        map_bytes: None,
        samples: None,
        shell_layers: None,
        compile_minutes: None,
        above,
        noise_free: None,
    }
}

/// `line` with what `renderer` played for `row` in `scene`: the maps'
/// bytes and compile minutes where they come from a compiled container
/// (PEM modes and REM; glass where it blends per-sample shell maps), the
/// samples, and glass's shell layers.
pub(super) fn with_facts(line: EvalRow, row: &Row, renderer: &Renderer, scene: &Scene) -> EvalRow {
    // Glass: the per-sample shell maps' bytes where it plays them (of the
    // room shell, or of every layer).
    let glass_samples = (row.mode == Mode::Hybrid)
        .then(|| {
            (renderer.glass.as_ref())
                .map_or(0, |g| g.sample_count().max(g.layer_sample_count()) as u32)
        })
        .filter(|&n| n > 0);
    let map_bytes = match row.mode {
        Mode::Rem | Mode::LayeredPem | Mode::SpherePem | Mode::Ptm => renderer.map_bytes,
        Mode::Hybrid => glass_samples.and(renderer.map_bytes),
        _ => None,
    };
    let samples = matches!(row.mode, Mode::LayeredPem | Mode::SpherePem | Mode::Ptm)
        .then(|| scene.orbit.sample_count())
        .or(glass_samples);
    let shell_layers = (row.mode == Mode::Hybrid)
        .then(|| renderer.glass.as_ref().map(|g| g.layer_count()))
        .flatten();
    EvalRow {
        map_bytes,
        samples,
        shell_layers,
        compile_minutes: samples.and(renderer.map_compile_minutes),
        ..line
    }
}
