//! `engine eval`: every mode and every knob that trades speed for accuracy,
//! measured against the traced gold standard on three kinds of views — on
//! the orbit (exactly on samples), between samples, and above the orbit
//! plane — beside its frame time. Each row is a set of the main command's
//! own flags, so `engine <flags>` replays what a row measured.

use crate::backend::{DeviceOptions, create_device};
use crate::cli::{Cli, EvalArgs, PlayArgs};
use crate::eval::metrics;
use crate::eval::plot::{ChartSpec, LegendPosition, Series, xy_chart};
use crate::eval::reference::{References, View as RefView};
use crate::eval::table::{EvalRow, EvalTable, ViewCounts};
use crate::perf::median;
use crate::play::{FrameSource, prepare_output, setup_mode};
use crate::renderer::Renderer;
use anyhow::{Context, Result, bail};
use clap::Parser;
use inference::scene::Scene;
use inference::trace::TraceSettings;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// The rows: a label and the play flags it stands for.
pub const ROWS: &[(&str, &str)] = &[
    ("static-em", "--mode static-em"),
    ("sphere-pem", "--mode sphere-pem"),
    ("sphere-pem nearest-sample", "--mode sphere-pem --no-blend"),
    ("layered-pem", "--mode layered-pem"),
    (
        "layered-pem nearest-sample",
        "--mode layered-pem --no-blend",
    ),
    (
        "layered-pem distant-only",
        "--mode layered-pem --distant-only",
    ),
    ("layered-pem em128", "--mode layered-pem --em-size 128"),
    ("layered-pem em64", "--mode layered-pem --em-size 64"),
    (
        "layered-pem bilinear",
        "--mode layered-pem --filtering bilinear",
    ),
    (
        "layered-pem nearest-texel",
        "--mode layered-pem --filtering nearest",
    ),
    ("layered-pem spacing2", "--mode layered-pem --spacing 2"),
    ("layered-pem spacing4", "--mode layered-pem --spacing 4"),
    ("layered-pem spacing8", "--mode layered-pem --spacing 8"),
    ("layered-pem uncompressed", "--mode layered-pem --maps exr"),
    ("ptm", "--mode ptm"),
    ("ptm nearest-sample", "--mode ptm --no-blend"),
    ("trace 4spp", "--mode trace --trace-spp 4"),
];

/// Where a view sits relative to the viewpoint samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    On,
    Between,
    Above,
}

#[derive(Clone, Copy, Debug)]
pub struct View {
    pub category: Category,
    pub azimuth_deg: f32,
    pub elevation_deg: f32,
}

/// `n` views per category, spread evenly along the orbit: on a sample,
/// half-way to the next, and on a sample's azimuth `elevation` above.
pub fn views(scene: &Scene, n: u32, elevation: f32) -> Vec<View> {
    let o = &scene.orbit;
    let last = o.samples.saturating_sub(1);
    let samples: Vec<u32> = (0..n)
        .map(|i| (((i as f32 + 0.5) / n as f32) * last as f32).round() as u32)
        .map(|k| k.min(last.saturating_sub(1)))
        .collect();
    let mut out = Vec::new();
    for (category, offset, up) in [
        (Category::On, 0.0, 0.0),
        (Category::Between, 0.5, 0.0),
        (Category::Above, 0.0, elevation),
    ] {
        for &k in &samples {
            out.push(View {
                category,
                azimuth_deg: o.angle_deg(k) + offset * o.step_deg,
                elevation_deg: up,
            });
        }
    }
    out
}

/// What one row measured on one view.
struct ViewResult {
    psnr_db: f64,
    flip: f64,
    frame_ms: f64,
}

pub fn eval(args: &EvalArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let data = args
        .data
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name));
    let out = args.out.clone().unwrap_or_else(|| data.join("eval"));
    prepare_output(&out)?;
    let rows: Vec<(&str, &str)> = ROWS
        .iter()
        .copied()
        .filter(|(label, _)| args.rows.is_empty() || args.rows.iter().any(|r| r == label))
        .collect();
    if rows.is_empty() {
        bail!(
            "--rows {:?}: no such rows (expected some of: {})",
            args.rows,
            ROWS.iter().map(|r| r.0).collect::<Vec<_>>().join(", ")
        );
    }
    let reflector = scene
        .objects
        .iter()
        .find(|o| o.em.is_some())
        .with_context(|| format!("{}: no reflector with [objects.em]", scene.source.display()))?
        .name
        .clone();
    let views = views(&scene, args.views, args.elevation);
    let (width, height) = args.size;

    // The gold standard of every view (traced once, cached).
    let reference_dir = out.join("reference");
    let tracing = References::new(
        &scene,
        &reference_dir,
        TraceSettings {
            width,
            height,
            spp: args.spp,
            progress: true,
            ..TraceSettings::default()
        },
    )?;
    let references = views
        .iter()
        .map(|v| tracing.get(RefView::new(v.azimuth_deg, v.elevation_deg), &reflector))
        .collect::<Result<Vec<_>>>()?;

    let device = create_device(&DeviceOptions {
        device_name: args.device.clone(),
        validate: args.validate,
    })?;
    let mut renderer = Renderer::new(&device, &scene, width, height)?;
    let mut table_rows = Vec::new();
    let mut pictures: Vec<(String, Vec<[f32; 4]>)> = Vec::new();
    let progress = indicatif::ProgressBar::new((rows.len() * views.len()) as u64).with_style(
        indicatif::ProgressStyle::with_template("eval {msg} [{bar:30}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut skipped = Vec::new();
    for (label, flags) in &rows {
        progress.set_message(label.to_string());
        let play = play_args(args, &data, flags)?;
        let mut source = match setup_mode(&play, &scene, &data, &mut renderer) {
            Ok(s) => s,
            Err(e) => {
                // A row whose maps are missing (e.g. sphere PEMs not inferred) is
                // reported, not fatal.
                skipped.push(format!("{label}: {e:#}"));
                progress.inc(views.len() as u64);
                continue;
            }
        };
        let mut results = Vec::new();
        for (i, (view, reference)) in views.iter().zip(&references).enumerate() {
            let eye = scene.orbit.eye(view.azimuth_deg, view.elevation_deg);
            let repeats = if matches!(source, FrameSource::Trace(..)) {
                1
            } else {
                source.frame(&mut renderer, &scene, eye)?; // maps resident, shaders warm
                renderer.settle(); // no decoding ahead while timing
                args.repeats
            };
            let mut times = Vec::new();
            let mut pixels = Vec::new();
            for _ in 0..repeats {
                let start = Instant::now();
                pixels = source.frame(&mut renderer, &scene, eye)?.1;
                times.push(start.elapsed().as_secs_f64() * 1e3);
            }
            let scores =
                metrics::scores(&reference.beauty, &pixels, width, height, &reference.mask)?;
            let (Some(psnr_db), Some(flip)) = (scores.psnr_db, scores.flip) else {
                bail!(
                    "view at azimuth {}°, elevation {}°: {reflector} covers no pixel",
                    view.azimuth_deg,
                    view.elevation_deg
                );
            };
            results.push((
                view.category,
                ViewResult {
                    psnr_db,
                    flip,
                    frame_ms: median(&times),
                },
            ));
            // The first view above the plane, for the side-by-side picture.
            if i == views
                .iter()
                .position(|v| v.category == Category::Above)
                .unwrap_or(0)
                && !label.contains(' ')
            {
                pictures.push((label.to_string(), pixels));
            }
            progress.inc(1);
        }
        let mean = |c: Category, f: fn(&ViewResult) -> f64| {
            let v: Vec<f64> = results
                .iter()
                .filter(|r| r.0 == c)
                .map(|r| f(&r.1))
                .collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let times: Vec<f64> = results.iter().map(|r| r.1.frame_ms).collect();
        table_rows.push(EvalRow {
            mode: label.split(' ').next().unwrap_or(label).to_string(),
            settings: settings_from_flags(label, flags),
            psnr_on_db: mean(Category::On, |r| r.psnr_db),
            psnr_between_db: mean(Category::Between, |r| r.psnr_db),
            psnr_above_db: mean(Category::Above, |r| r.psnr_db),
            flip_on: mean(Category::On, |r| r.flip),
            flip_between: mean(Category::Between, |r| r.flip),
            flip_above: mean(Category::Above, |r| r.flip),
            frame_ms: median(&times),
            frame_ms_p95: Some(percentile(&times, 0.95)),
            views: Some(ViewCounts {
                on: args.views,
                between: args.views,
                above: args.views,
            }),
            map_bytes: None,
        });
    }
    progress.finish_and_clear();
    let eval_table = EvalTable { rows: table_rows };
    let json_path = out.join("eval.json");
    eval_table.write(&json_path)?;
    let plot_path = out.join("tradeoff.png");
    tradeoff_chart(&plot_path, &eval_table, &device.name, args)?;
    if let Some(above) = views.iter().position(|v| v.category == Category::Above) {
        let gold = references[above].beauty.clone();
        pictures.push(("gold (traced)".into(), gold));
        side_by_side(
            &out.join("modes_above.png"),
            &pictures,
            &references[above].mask,
            width,
            height,
        )?;
    }
    let mut text = format!(
        "{} | {} {width}x{height} | {} views per category, above = +{}°, reference {} spp\n",
        device.name, scene.name, args.views, args.elevation, args.spp
    );
    text += &eval_table.to_markdown();
    for s in &skipped {
        text += &format!("skipped {s}\n");
    }
    text += &format!(
        "wrote {} and {}\n",
        json_path.display(),
        plot_path.display()
    );
    Ok(text)
}

/// The main command's arguments for one row (plus the run's common ones).
fn play_args(args: &EvalArgs, data: &Path, flags: &str) -> Result<PlayArgs> {
    let size = format!("{}x{}", args.size.0, args.size.1);
    let mut argv: Vec<String> = ["engine", "--scene", &args.scene, "--size", &size]
        .map(String::from)
        .to_vec();
    argv.extend(["--out".into(), data.display().to_string()]);
    if let Some(d) = &args.device {
        argv.extend(["--device".into(), d.clone()]);
    }
    argv.extend(flags.split_whitespace().map(String::from));
    let cli = Cli::try_parse_from(&argv).with_context(|| format!("row flags {flags:?}"))?;
    Ok(cli.play)
}

/// One picture: each mode's frame cropped around the reflector, side by side.
fn side_by_side(
    path: &Path,
    pictures: &[(String, Vec<[f32; 4]>)],
    mask: &[bool],
    width: u32,
    height: u32,
) -> Result<()> {
    let (w, h) = (width as usize, height as usize);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (x, y) = (i % w, i / w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    if x0 > x1 {
        (x0, y0, x1, y1) = (0, 0, w - 1, h - 1);
    }
    let margin = 8;
    let (x0, y0) = (x0.saturating_sub(margin), y0.saturating_sub(margin));
    let (x1, y1) = ((x1 + margin).min(w - 1), (y1 + margin).min(h - 1));
    let (cw, ch) = (x1 - x0 + 1, y1 - y0 + 1);
    let n = pictures.len();
    let mut mosaic = vec![[0.0f32; 4]; cw * n * ch];
    for (k, (_, pixels)) in pictures.iter().enumerate() {
        for y in 0..ch {
            for x in 0..cw {
                mosaic[y * cw * n + k * cw + x] = pixels[(y0 + y) * w + x0 + x];
            }
        }
    }
    crate::capture::write_png(path, (cw * n) as u32, ch as u32, &mosaic)?;
    let labels: Vec<&str> = pictures.iter().map(|p| p.0.as_str()).collect();
    std::fs::write(path.with_extension("txt"), labels.join(" | ") + "\n")
        .with_context(|| format!("writing {}", path.with_extension("txt").display()))?;
    Ok(())
}

/// A row's settings: its label and the flags it adds to the defaults.
fn settings_from_flags(label: &str, flags: &str) -> BTreeMap<String, serde_json::Value> {
    let mut settings = BTreeMap::new();
    settings.insert("label".into(), serde_json::Value::from(label));
    let words: Vec<&str> = flags.split_whitespace().collect();
    let mut i = 0;
    while i < words.len() {
        let key = words[i].trim_start_matches("--").replace('-', "_");
        match words.get(i + 1).filter(|w| !w.starts_with("--")) {
            Some(value) => {
                let v = value
                    .parse::<u64>()
                    .map_or_else(|_| serde_json::Value::from(*value), serde_json::Value::from);
                if key != "mode" {
                    settings.insert(key, v);
                }
                i += 2;
            }
            None => {
                settings.insert(key, serde_json::Value::Bool(true));
                i += 1;
            }
        }
    }
    settings
}

/// The `q` quantile (nearest rank) of `values`.
fn percentile(values: &[f64], q: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

/// PSNR between samples and above the plane against frame time, one point
/// per row (the traced row is off the time scale and left out).
fn tradeoff_chart(path: &Path, table: &EvalTable, device: &str, args: &EvalArgs) -> Result<()> {
    let rows: Vec<&EvalRow> = table.rows.iter().filter(|r| r.mode != "trace").collect();
    let label = |r: &EvalRow| {
        r.settings
            .get("label")
            .and_then(|v| v.as_str())
            .unwrap_or(&r.mode)
            .to_string()
    };
    let mut spec = ChartSpec::new(
        &format!(
            "Speed against accuracy, {} {}x{} ({device})",
            table.rows.first().map_or("", |_| args.scene.as_str()),
            args.size.0,
            args.size.1
        ),
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
