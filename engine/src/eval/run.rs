//! `engine eval`: every row of [`rows_for`] measured against the traced
//! gold standard on three kinds of views — on the orbit, between samples,
//! above the orbit plane — beside its frame time.

use super::chart::tradeoff_chart;
use super::metrics;
use super::pictures::side_by_side;
use super::reference::{ReferenceImage, References, View as RefView};
use super::relight::{RELIGHT_ROW, RelightOptions, RelightReport};
use super::row_scores::{table_row, with_facts};
use super::rows::{Row, rows_for};
use super::table::EvalTable;
use super::views::{Category, View, views};
use crate::options::RunPlace;
use crate::play::{FrameSource, Session, compile_context, setup_mode};
use crate::relight::GridSettings;
use crate::util::stats::median;
use anyhow::{Result, bail};
use std::path::PathBuf;
use std::time::Instant;

/// What to measure.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Where the eval's files go [default: `<data>/eval`].
    pub out: Option<PathBuf>,
    /// Views per category, spread evenly along the orbit.
    pub views: u32,
    /// Elevation of the "above" views over the orbit plane, degrees.
    /// Elevations of the views above the plane (the first is the
    /// `*_above` fields'; each has its own `above[]` entry).
    pub elevations: Vec<f32>,
    /// Samples per pixel of the traced references.
    pub spp: u32,
    /// Timed frames per view and row (after one untimed frame).
    pub repeats: u32,
    /// Only these rows (labels) [default: all]; `relight` selects the
    /// relighting rows (k = 9, 16, 25 at held-out lights).
    pub rows: Vec<String>,
    /// What the relighting rows trace and project.
    pub relight: GridSettings,
}

/// What one row measured on one view.
pub(super) struct ViewResult {
    pub(super) category: Category,
    pub(super) elevation_deg: f32,
    pub(super) psnr_db: f64,
    pub(super) flip: f64,
    /// Every pixel, as the PNG shows it.
    pub(super) frame: metrics::FrameScores,
    pub(super) frame_ms: f64,
}

/// Runs the rows of `opts` in `place` (whose output folder holds the
/// compiled maps); returns the printed table.
pub fn eval(place: &RunPlace, opts: &EvalOptions) -> Result<String> {
    let Session {
        scene,
        out: data,
        device,
        mut renderer,
        ..
    } = Session::open(place)?;
    let (rows, relight_wanted) = selected_rows(&opts.rows, &scene)?;
    let rows: Vec<Row> = rows
        .into_iter()
        .map(|r| r.against_references(opts.spp))
        .collect();
    let out = opts.out.clone().unwrap_or_else(|| data.join("eval"));
    crate::util::files::claim_dir(&out)?;
    let relight = match relight_wanted {
        true => Some(relight_rows(&scene, place, opts, &out)?),
        false => None,
    };
    let reflectors = reflector_names(&scene)?;
    let reflector = reflectors.join("+");
    let views = views(&scene, opts.views, &opts.elevations);
    let references = match rows.is_empty() {
        true => Vec::new(),
        false => references(&scene, &views, place.size, opts.spp, &out, &reflectors)?,
    };
    let run = RowRun {
        views: &views,
        references: &references,
        repeats: opts.repeats,
        reflector: &reflector,
    };
    let ctx = compile_context(place, &scene, &data);
    let progress = progress_bar((rows.len() * views.len()) as u64);
    let (mut table_rows, mut pictures, mut skipped) = (Vec::new(), Vec::new(), Vec::new());
    for row in &rows {
        progress.set_message(row.label.clone());
        let mut source = match setup_mode(&ctx, &mut renderer, row.mode, &row.pem, row.trace) {
            Ok(s) => s,
            Err(e) => {
                // A row whose maps cannot be made is reported, not fatal.
                skipped.push(format!("{}: {e:#}", row.label));
                progress.inc(views.len() as u64);
                continue;
            }
        };
        let (results, frames) = run.measure_row(&mut source, &mut renderer, &scene, &progress)?;
        if !row.label.contains(' ') {
            pictures.push((row.label.clone(), frames));
        }
        let line = table_row(row, &results, opts.views);
        table_rows.push(with_facts(line, row, &renderer, &scene));
    }
    progress.finish_and_clear();
    super::noise::attach(&mut table_rows);
    let table = EvalTable {
        rows: table_rows,
        relight,
    };
    let title = format!(
        "Speed against accuracy, {} {}x{} ({})",
        scene.name, place.size.0, place.size.1, device.name
    );
    let written = write_outputs(&out, &table, &title, &run, pictures, place.size)?;
    let head = format!("{} | {}", device.name, scene.name);
    Ok(summary(head, place, opts, &table, &skipped) + &written)
}

/// What `engine eval` prints: the tables and the rows it skipped.
fn summary(
    mut text: String,
    place: &RunPlace,
    opts: &EvalOptions,
    table: &EvalTable,
    skipped: &[String],
) -> String {
    if !table.rows.is_empty() {
        text += &format!(
            " {}x{} | {} views per category, above = +{:?}°, reference {} spp\n",
            place.size.0, place.size.1, opts.views, opts.elevations, opts.spp
        );
        text += &table.to_markdown();
        text += &table.above_markdown();
        text += &super::noise::markdown(&table.rows);
    }
    text += &table
        .relight
        .as_ref()
        .map_or_else(String::new, RelightReport::to_markdown);
    for s in skipped {
        text += &format!("skipped {s}\n");
    }
    text
}

fn progress_bar(len: u64) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(len).with_style(
        indicatif::ProgressStyle::with_template("eval {msg} [{bar:30}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    )
}

/// The objects the rows score together: every one with an EM or glass
/// table (a teapot's lid and body are one reflector to a viewer).
pub fn reflector_names(scene: &inference::scene::Scene) -> Result<Vec<String>> {
    let names: Vec<String> = scene
        .objects
        .iter()
        .filter(|o| o.em.is_some() || o.glass.is_some())
        .map(|o| o.name.clone())
        .collect();
    if names.is_empty() {
        let origin = &scene.origin;
        bail!("{origin}: no reflector with [objects.em] or glass with [objects.glass]");
    }
    Ok(names)
}

/// The traced gold standard of every view (traced once, cached under
/// `out/reference`).
fn references(
    scene: &inference::scene::Scene,
    views: &[View],
    size: (u32, u32),
    spp: u32,
    out: &std::path::Path,
    reflectors: &[String],
) -> Result<Vec<ReferenceImage>> {
    let settings = super::reference::reference_settings(size, spp);
    let tracing = References::new(scene, &out.join("reference"), settings)?;
    views
        .iter()
        .map(|v| tracing.get_all(RefView::new(v.azimuth_deg, v.elevation_deg), reflectors))
        .collect()
}

/// eval.json, the chart and the side-by-side picture; returns what it says.
fn write_outputs(
    out: &std::path::Path,
    table: &EvalTable,
    title: &str,
    run: &RowRun,
    pictures: Vec<(String, Vec<Pixels>)>,
    (width, height): (u32, u32),
) -> Result<String> {
    let json_path = out.join("eval.json");
    table.write(&json_path)?;
    let plot_path = out.join(match table.rows.is_empty() {
        true => "relight.png",
        false => "tradeoff.png",
    });
    if !table.rows.is_empty() {
        tradeoff_chart(&plot_path, table, title)?;
    }
    // One picture per elevation: the first's keeps its old name.
    for (j, &above) in run.above().iter().enumerate() {
        let Some(reference) = run.references.get(above) else {
            continue;
        };
        let mut row: Vec<(String, Pixels)> = pictures
            .iter()
            .filter_map(|(label, frames)| Some((label.clone(), frames.get(j)?.clone())))
            .collect();
        row.push(("gold (traced)".into(), reference.beauty.clone()));
        let name = match j {
            0 => "modes_above.png".to_owned(),
            _ => format!("modes_above_{:.0}.png", run.views[above].elevation_deg),
        };
        side_by_side(&out.join(name), &row, &reference.mask, width, height)?;
    }
    Ok(format!(
        "wrote {} and {}\n",
        json_path.display(),
        plot_path.display()
    ))
}

/// A frame's linear RGBA pixels.
type Pixels = Vec<[f32; 4]>;

/// What every row is measured on.
struct RowRun<'a> {
    views: &'a [View],
    references: &'a [ReferenceImage],
    repeats: u32,
    reflector: &'a str,
}

impl RowRun<'_> {
    /// The first view above the plane at each elevation, in the order of
    /// the views (the side-by-side pictures').
    fn above(&self) -> Vec<usize> {
        let mut firsts: Vec<usize> = Vec::new();
        for (i, v) in self.views.iter().enumerate() {
            let seen = firsts
                .iter()
                .any(|&f| self.views[f].elevation_deg == v.elevation_deg);
            if v.category == Category::Above && !seen {
                firsts.push(i);
            }
        }
        firsts
    }

    /// One row on every view; with its frames of [`RowRun::above`]'s views.
    fn measure_row(
        &self,
        source: &mut FrameSource,
        renderer: &mut crate::renderer::Renderer,
        scene: &inference::scene::Scene,
        progress: &indicatif::ProgressBar,
    ) -> Result<(Vec<ViewResult>, Vec<Pixels>)> {
        let mut results = Vec::new();
        let above = self.above();
        let mut frames = Vec::new();
        for (i, (view, reference)) in self.views.iter().zip(self.references).enumerate() {
            let (result, pixels) = measure(
                source,
                renderer,
                scene,
                view,
                reference,
                self.repeats,
                self.reflector,
            )?;
            results.push(result);
            if above.contains(&i) {
                frames.push(pixels);
            }
            progress.inc(1);
        }
        Ok((results, frames))
    }
}

/// The rows whose labels are in `wanted` (all when empty).
/// The rendered rows `wanted` names (all when empty) and whether it names
/// the relighting rows (also when empty).
fn selected_rows(wanted: &[String], scene: &inference::scene::Scene) -> Result<(Vec<Row>, bool)> {
    let all = rows_for(scene);
    let rows: Vec<Row> = all
        .iter()
        .filter(|r| wanted.is_empty() || wanted.contains(&r.label))
        .cloned()
        .collect();
    let relight = wanted.is_empty() || wanted.iter().any(|w| w == RELIGHT_ROW);
    let unknown: Vec<&String> = wanted
        .iter()
        .filter(|w| *w != RELIGHT_ROW && !all.iter().any(|r| &r.label == *w))
        .collect();
    if !unknown.is_empty() || (rows.is_empty() && !relight) {
        bail!(
            "--rows {unknown:?}: no such rows (expected some of: {}, {RELIGHT_ROW})",
            all.iter()
                .map(|r| r.label.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok((rows, relight))
}

/// The relighting rows: `engine relight`'s measurement on `opts.relight`,
/// its cache and images under `out/relight`, its chart `out/relight.png`.
fn relight_rows(
    scene: &inference::scene::Scene,
    place: &RunPlace,
    opts: &EvalOptions,
    out: &std::path::Path,
) -> Result<RelightReport> {
    let options = RelightOptions {
        settings: opts.relight,
        out: out.to_path_buf(),
        frames: 100,
        device: place.device.clone(),
        progress: true,
        ratio: Some(crate::relight::codec::DEFAULT_RATIO),
    };
    let report = super::relight::run(scene, &options)?;
    let title = format!("Relighting {} with spherical harmonics", scene.name);
    report.chart(&out.join("relight.png"), &title)?;
    Ok(report)
}

/// One row's frames of one view: timed (maps resident, no decoding
/// ahead), scored against the reference; returns the last frame too.
fn measure(
    source: &mut FrameSource,
    renderer: &mut crate::renderer::Renderer,
    scene: &inference::scene::Scene,
    view: &View,
    reference: &ReferenceImage,
    repeats: u32,
    reflector: &str,
) -> Result<(ViewResult, Vec<[f32; 4]>)> {
    let eye = scene.orbit.eye(view.azimuth_deg, view.elevation_deg);
    let repeats = if matches!(source, FrameSource::Trace(..)) {
        1
    } else {
        renderer.set_next_view(eye, scene.orbit.view(eye));
        source.draw(renderer, scene, eye)?; // maps resident, shaders warm
        renderer.settle(); // no decoding ahead while timing
        repeats
    };
    let mut times = Vec::new();
    let mut pixels = Vec::new();
    for i in 0..repeats {
        if i + 1 < repeats {
            // Frames in flight, as in playback: the next frame's CPU work
            // (glass paths) overlaps this one.
            renderer.set_next_view(eye, scene.orbit.view(eye));
        }
        let start = Instant::now();
        pixels = source.frame(renderer, scene, eye)?.1;
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let (width, height) = renderer.size();
    let scores = metrics::scores(&reference.beauty, &pixels, width, height, &reference.mask)?;
    let (Some(psnr_db), Some(flip)) = (scores.psnr_db, scores.flip) else {
        bail!(
            "view at azimuth {}°, elevation {}°: {reflector} covers no pixel",
            view.azimuth_deg,
            view.elevation_deg
        );
    };
    let result = ViewResult {
        category: view.category,
        elevation_deg: view.elevation_deg,
        psnr_db,
        flip,
        frame: metrics::frame_scores(&reference.beauty, &pixels, width, height)?,
        frame_ms: median(&times),
    };
    Ok((result, pixels))
}
