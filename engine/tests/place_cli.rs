//! `engine place` end to end on the tiny scene with 5 dense samples: it
//! refines from the two ends, scores views no dense solve saw, stops at
//! the budget, compares with an even placement, and writes a placed scene
//! file that compiles and plays only its own samples.

mod common;

use common::{output_text, run_engine, tiny_scene, traced_views};
use serde_json::json;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8")
}

/// The tiny scene in `dir`, and a copy named `name` whose 3 orbit samples
/// are replaced by `orbit` (the dense grid placement chooses from).
fn dense_tiny(dir: &Path, name: &str, orbit: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let tiny = tiny_scene(dir);
    let text = std::fs::read_to_string(&tiny).expect("tiny scene");
    let dense = dir.join(name);
    std::fs::write(&dense, text.replacen("samples = 3", orbit, 1)).expect("write");
    (tiny, dense)
}

/// Runs `engine args` (with `--validate`), expects success without
/// validation messages, and returns `out`'s placement.json.
fn placement(args: &[&str], out: &Path) -> serde_json::Value {
    let o = run_engine(args);
    let log = output_text(&o);
    assert!(
        o.status.success() && log.contains("validation messages: 0"),
        "{log}"
    );
    serde_json::from_slice(&std::fs::read(out.join("placement.json")).expect("json")).expect("JSON")
}

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn placement_splits_the_worst_interval_and_its_scene_plays() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (_, dense) = dense_tiny(dir.path(), "dense.toml", "samples = 5");
    let (data, out) = (dir.path().join("data"), dir.path().join("place"));
    let report = placement(
        &[
            "place",
            "--scene",
            s(&dense),
            "--size",
            "64x48",
            "--data",
            s(&data),
            "--out",
            s(&out),
            "--start",
            "2",
            "--max-samples",
            "3",
            "--max-bytes",
            "1000000000000",
            "--max-minutes",
            "100000",
            "--target-db",
            "99",
            "--spp",
            "4",
            "--validate",
        ],
        &out,
    );
    assert_eq!(report["stop"], "budget", "{report}");
    let lines: Vec<u64> = report["placed"]["lines"]
        .as_array()
        .expect("lines")
        .iter()
        .filter_map(|l| l.as_u64())
        .collect();
    assert_eq!(lines, [0, 2, 4], "{report}");
    // The whole span was scored first (at line 2), then each half.
    let measured = report["measured"].as_array().expect("measured");
    let probes: Vec<u64> = measured
        .iter()
        .filter_map(|m| m["probe"].as_u64())
        .collect();
    assert_eq!(probes, [2, 1, 3], "{report}");
    let db: Vec<f64> = measured.iter().map(|m| num(&m["psnr_db"])).collect();
    assert!(db.iter().all(|d| d.is_finite() && *d > 10.0), "{db:?}");
    // Each is scored half a line past its middle line, where no dense
    // solve stacked a view (at line 1 and 3 both neighbours' had).
    assert_eq!(
        report["placed"]["probes_deg"],
        serde_json::json!([1.5, 3.5]),
        "{report}"
    );
    // The even placement of 3 samples is the same here: the same scores.
    assert_eq!(report["even"]["lines"], report["placed"]["lines"]);
    assert_eq!(
        num(&report["even"]["worst_db"]),
        num(&report["placed"]["worst_db"])
    );
    assert!(out.join("placement.png").is_file());
    assert_byte_budget(&report, &dense, &data);
    assert_minutes_budget(&report, &dense, &data);
    assert_placed_scene_plays(&out.join("teapot_placed.toml"), &dir.path().join("play"));
}

/// The byte budget takes its bytes per sample from the dense container
/// (5 samples) and estimates the placed 3 from it; a budget below two
/// samples' worth is refused, naming what fits, with no placement written.
fn assert_byte_budget(report: &serde_json::Value, dense: &Path, data: &Path) {
    let container = std::fs::metadata(data.join("teapot.ptxc"))
        .expect("dense container")
        .len() as f64;
    let per_sample = num(&report["max_bytes"]["per_sample"]);
    assert!((per_sample * 5.0 - container).abs() < 1.0, "{report}");
    let estimated = num(&report["estimated_bytes"]);
    assert!(
        (estimated - (per_sample * 3.0).round()).abs() < 0.5,
        "{report}"
    );
    let small = ((per_sample * 1.5) as u64).to_string();
    assert_refused(
        dense,
        data,
        "--max-bytes",
        &small,
        "B a sample, so 1 sample fit",
    );
}

/// `engine place` with `option value` is refused, the log naming both and
/// `expected`, no placement written.
fn assert_refused(dense: &Path, data: &Path, option: &str, value: &str, expected: &str) {
    let out = data.join(format!("refused{option}"));
    let o = run_engine(&[
        "place",
        "--scene",
        s(dense),
        "--size",
        "64x48",
        "--data",
        s(data),
        "--out",
        s(&out),
        "--start",
        "2",
        option,
        value,
        "--spp",
        "4",
    ]);
    let log = output_text(&o);
    assert!(!o.status.success(), "{log}");
    assert!(
        log.contains(&format!("{option} {value}")) && log.contains(expected),
        "{log}"
    );
    assert!(!out.join("placement.json").exists(), "{log}");
}

/// The compile-minutes budget the same way, from the dense compile's
/// records: the estimate is the minutes per sample times 3, and a budget
/// of 1.5 samples' minutes is refused naming what fits.
fn assert_minutes_budget(report: &serde_json::Value, dense: &Path, data: &Path) {
    let per_sample = num(&report["max_minutes"]["per_sample"]);
    assert!(per_sample > 0.0 && per_sample.is_finite(), "{report}");
    let estimated = num(&report["estimated_minutes"]);
    assert!((estimated - per_sample * 3.0).abs() < 1e-9, "{report}");
    let small = format!("{}", per_sample * 1.5);
    assert_refused(
        dense,
        data,
        "--max-minutes",
        &small,
        "min a sample, so 1 sample fit",
    );
}

/// The placed scene compiles its 3 samples only (eyes at dense lines 0, 2
/// and 4), stacking offset views, and plays with validation on.
fn assert_placed_scene_plays(scene: &Path, out: &Path) {
    let text = std::fs::read_to_string(scene).expect("placed scene written");
    assert!(text.contains("azimuths_deg = [0.0, 2.0, 4.0]"), "{text}");
    let o = run_engine(&[
        "--scene",
        s(scene),
        "--size",
        "64x48",
        "--frames",
        "4",
        "--warmup",
        "1",
        "--out",
        s(out),
        "--validate",
    ]);
    let log = output_text(&o);
    assert!(
        o.status.success() && log.contains("validation messages: 0"),
        "{log}"
    );
    let infer = out.join("infer");
    assert!(infer.join("sample_0002").is_dir(), "{log}");
    assert!(!infer.join("sample_0003").exists(), "{log}");
    // Its solves stack views traced 1° (the dense spacing) either side of
    // each sample, as the scored maps' solves did, not its own neighbours;
    // samples 2° apart share the view between them: 4 views for 3 samples.
    assert!(text.contains("neighbour_deg = 1.0"), "{text}");
    let views = traced_views(out);
    let mut expected = ["-1.000", "+1.000", "+3.000", "+5.000"]
        .map(|a| format!("view_az{a}_el+0.000.exr"))
        .to_vec();
    expected.sort();
    assert_eq!(views, expected, "{log}");
}

#[test]
fn a_2d_viewpoint_space_is_refused_before_anything_compiles() {
    let dir = tempfile::tempdir().expect("temp dir");
    let data = dir.path().join("data");
    let o = run_engine(&["place", "--scene", "teapot_rings", "--data", s(&data)]);
    let log = output_text(&o);
    assert!(!o.status.success(), "{log}");
    assert!(
        log.contains("4 rings") && log.contains("1D orbit") && log.contains("--rings"),
        "{log}"
    );
    // Refused before the session claims its folder: nothing left behind.
    assert!(!data.exists(), "{log}");
}

#[test]
fn a_budget_below_the_start_lines_is_refused_before_anything_compiles() {
    let dir = tempfile::tempdir().expect("temp dir");
    let data = dir.path().join("data");
    // The shipped teapot's rings skip lines: place starts from a full grid.
    let o = run_engine(&["place", "--scene", "teapot", "--data", s(&data)]);
    let log = output_text(&o);
    assert!(!o.status.success(), "{log}");
    assert!(
        log.contains("ring_line_every") && log.contains("built-in scene 'teapot'"),
        "{log}"
    );
    let tiny = tiny_scene(dir.path());
    let text = std::fs::read_to_string(&tiny).expect("tiny scene");
    let dense = dir.path().join("dense.toml");
    std::fs::write(&dense, text.replacen("samples = 3", "samples = 100", 1)).expect("write");
    let o = run_engine(&[
        "place",
        "--scene",
        s(&dense),
        "--data",
        s(&data),
        "--start",
        "5",
        "--max-samples",
        "3",
    ]);
    let log = output_text(&o);
    assert!(!o.status.success(), "{log}");
    assert!(
        log.contains("--max-samples") && log.contains("dense.toml"),
        "{log}"
    );
    assert!(!data.exists(), "{log}");
}

/// `--rings` on a 2D grid of 3 azimuth lines × 5 rings 5° apart: it places
/// rings, each with every line, scoring the views half way between dense
/// rings on every line, within a budget of samples (9 = 3 rings), and
/// writes `ring_elevations_deg`. Then `--grid` on the same compile.
#[test]
fn rings_are_placed_with_every_azimuth_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rings = "samples = 3\nrings = 5\nring_step_deg = 5.0";
    let (tiny, dense) = dense_tiny(dir.path(), "rings.toml", rings);
    let (data, out) = (dir.path().join("data"), dir.path().join("place"));
    let args = [
        "place",
        "--rings",
        "--scene",
        s(&dense),
        "--size",
        "64x48",
        "--data",
        s(&data),
        "--out",
        s(&out),
        "--start",
        "2",
        "--max-samples",
        "10",
        "--target-db",
        "99",
        "--spp",
        "4",
        "--validate",
    ];
    let report = placement(&args, &out);
    assert_eq!(
        (&report["axis"], &report["stop"]),
        (&serde_json::json!("rings"), &serde_json::json!("budget")),
        "{report}"
    );
    let placed = &report["placed"];
    assert_eq!(placed["lines"], serde_json::json!([0, 2, 4]), "{report}");
    assert_eq!(placed["samples"], 9, "{report}");
    assert_eq!(
        placed["elevations_deg"],
        serde_json::json!([0.0, 10.0, 20.0])
    );
    assert_eq!(
        placed["probes_deg"],
        serde_json::json!([7.5, 17.5]),
        "{report}"
    );
    let probes: Vec<u64> = report["measured"]
        .as_array()
        .expect("measured")
        .iter()
        .filter_map(|m| m["probe"].as_u64())
        .collect();
    assert_eq!(probes, [2, 1, 3], "{report}");
    let scene = out.join("teapot_placed.toml");
    let text = std::fs::read_to_string(&scene).expect("placed scene written");
    assert!(
        text.contains("ring_elevations_deg = [0.0, 10.0, 20.0]")
            && !text
                .lines()
                .any(|l| l.starts_with("ring_step_deg") || l.starts_with("rings")),
        "{text}"
    );
    let placed = inference::scene::Scene::load(s(&scene)).expect("placed scene loads");
    assert_eq!(placed.orbit.sample_count(), 9);
    assert_grid_placement(&dense, &data, &dir.path().join("grid"));
    assert_rings_refused(&tiny, &dense, &data);
}

/// `--rings` on a 1D orbit is refused, naming the file and the fix, and so
/// is starting from every dense ring (nothing left to place).
fn assert_rings_refused(tiny: &Path, dense: &Path, data: &Path) {
    // A 1D orbit is refused with --rings, naming the file and the fix.
    let o = run_engine(&["place", "--rings", "--scene", s(tiny), "--data", s(data)]);
    let log = output_text(&o);
    assert!(!o.status.success() && log.contains("one ring"), "{log}");
    // Starting from every dense ring leaves nothing to place.
    let o = run_engine(&[
        "place",
        "--rings",
        "--scene",
        s(dense),
        "--data",
        s(data),
        "--start",
        "5",
    ]);
    let log = output_text(&o);
    assert!(
        !o.status.success() && log.contains("--start 5 places all 5 dense rings"),
        "{log}"
    );
}

/// `--grid` on the 3 lines × 5 rings compile: from the 2 × 2 corners
/// (lines 0 and 2, rings 0 and 4) one split fits a budget of 6 samples —
/// a line (3 × 2) or a ring (2 × 3), whichever interval scored worse —
/// it is compared with the balanced even 2 × 3, and the placed scene names
/// both lists.
fn assert_grid_placement(dense: &Path, data: &Path, out: &Path) {
    let report = placement(
        &[
            "place",
            "--grid",
            "--scene",
            s(dense),
            "--size",
            "64x48",
            "--data",
            s(data),
            "--out",
            s(out),
            "--start",
            "2",
            "--max-samples",
            "6",
            "--target-db",
            "99",
            "--spp",
            "4",
            "--validate",
        ],
        out,
    );
    assert_eq!(
        (&report["axis"], &report["stop"]),
        (&serde_json::json!("grid"), &serde_json::json!("budget")),
        "{report}"
    );
    let splits = report["splits"].as_array().expect("splits");
    assert_eq!(splits.len(), 1, "{report}");
    let placed = &report["placed"];
    assert_eq!(placed["samples"], 6, "{report}");
    // Each start interval was scored on both lines of the other axis (4
    // views); a ring split adds its two halves on both lines and the
    // line interval on the new ring (5 more), a line split the rings'
    // interval on the new line (1 more). The even grid compared is the
    // balanced 2 lines × 3 rings: the placed grid after a ring split (no
    // view scored twice), else 5 views more.
    let (lines, rings, views) = match splits[0]["axis"].as_str() {
        Some("rings") => (json!([0, 2]), json!([0, 2, 4]), 9),
        Some("azimuth") => (json!([0, 1, 2]), json!([0, 4]), 10),
        other => panic!("split axis {other:?}: {report}"),
    };
    assert_eq!((&placed["lines"], &placed["rings"]), (&lines, &rings));
    assert_eq!(report["views_scored"], views, "{report}");
    let even = &report["even"];
    assert_eq!(
        (&even["lines"], &even["rings"], &even["samples"]),
        (&json!([0, 2]), &json!([0, 2, 4]), &json!(6)),
        "{report}"
    );
    let scene = out.join("teapot_placed.toml");
    let text = std::fs::read_to_string(&scene).expect("placed scene written");
    assert!(
        text.contains("azimuths_deg = [") && text.contains("ring_elevations_deg = ["),
        "{text}"
    );
    let scene = inference::scene::Scene::load(s(&scene)).expect("placed scene loads");
    assert_eq!(scene.orbit.sample_count(), 6);
    // A 1D orbit has no grid to place.
    let none = out.join("teapot-data");
    let tiny = dense.with_file_name("tiny.toml"); // dense_tiny's 1D scene
    let o = run_engine(&["place", "--grid", "--scene", s(&tiny), "--data", s(&none)]);
    let log = output_text(&o);
    assert!(!o.status.success() && log.contains("--grid"), "{log}");
}
