//! `engine infer` end to end on a small view: traced targets, probe renders
//! with validation on, maps and report.json; bad input fails cleanly.

use std::process::{Command, Output};

fn engine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

/// A one-sample report: probe renders, the A-vs-render check, the three
/// layers in order with finite PSNRs, and least squares beating forward
/// mapping on the distant layer beside its static-EM baseline.
fn assert_sample_report(report: &serde_json::Value) {
    assert!(report["probe_renders"].as_u64().is_some_and(|n| n > 2));
    assert!(
        report["a_vs_render_psnr_db"]
            .as_f64()
            .is_some_and(|v| v >= 140.0),
        "{report}"
    );
    assert!(report["solve_s"].as_f64().is_some_and(|v| v >= 0.0));
    let layers = report["layers"].as_array().expect("layers");
    let names: Vec<&str> = layers.iter().filter_map(|l| l["name"].as_str()).collect();
    assert_eq!(
        names,
        [
            "teapot.specular_distant",
            "teapot.specular_local",
            "teapot.ptm"
        ]
    );
    for l in layers {
        let ls = l["psnr_db"]["least_squares"].as_f64().expect("LS PSNR");
        let fm = l["psnr_db"]["forward_mapping"].as_f64().expect("FM PSNR");
        assert!(ls.is_finite() && fm.is_finite() && ls > 5.0, "{l}");
    }
    // Distant layer: least squares must beat forward mapping (the thesis's
    // claim); the static-EM baseline is reported beside them.
    let distant = &layers[0];
    assert!(
        distant["psnr_db"]["static_em"]
            .as_f64()
            .is_some_and(f64::is_finite),
        "{distant}"
    );
    assert!(
        layers[1]["psnr_db"].get("static_em").is_none(),
        "static EM is a distant-layer baseline"
    );
    assert!(
        distant["psnr_db"]["least_squares"].as_f64()
            > distant["psnr_db"]["forward_mapping"].as_f64(),
        "{distant}"
    );
}

#[test]
fn infers_em_layers_and_ptm_of_a_sample_and_reports() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("infer");
    let traces = dir.path().join("trace");
    let o = engine(&[
        "infer",
        "--scene",
        "teapot",
        "--sample",
        "1",
        "--size",
        "96x72",
        "--em-size",
        "16",
        "--spp",
        "2",
        "--out",
        out.to_str().expect("utf-8"),
        "--trace-dir",
        traces.to_str().expect("utf-8"),
        "--validate",
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{}\n{stdout}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    assert!(
        traces.join("sample_0001.exr").is_file(),
        "target traced on demand"
    );
    for layer in [
        "teapot.specular_distant",
        "teapot.specular_local",
        "teapot.ptm",
    ] {
        assert!(
            out.join("sample_0001")
                .join(format!("{layer}.exr"))
                .is_file(),
            "{layer}"
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).expect("report.json"))
            .expect("JSON");
    assert_sample_report(&report);
}

/// The teapot scene with only `samples` orbit samples, written into `dir`.
fn small_scene(dir: &std::path::Path, samples: u32) -> String {
    let text = inference::scene::shipped("teapot").expect("built-in teapot");
    let text = inference::scene::shipped::without_views_above(text);
    let line = format!("samples = {samples}");
    let text = text
        .lines()
        .map(|l| {
            if l.trim() == "samples = 100" {
                &line
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(text.contains(&line), "scene fields moved");
    let path = dir.join("small.toml");
    std::fs::write(&path, text).expect("write scene");
    path.to_str().expect("utf-8").to_string()
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).expect("read JSON")).expect("JSON")
}

fn layer_names(report: &serde_json::Value) -> Vec<String> {
    report["layers"]
        .as_array()
        .expect("layers")
        .iter()
        .filter_map(|l| l["name"].as_str().map(String::from))
        .collect()
}

/// The keys of the distant, local and PTM maps of samples 0 and 1.
fn map_keys(out: &std::path::Path) -> Vec<String> {
    let key = |k: u32, name: &str| {
        std::fs::read_to_string(out.join(format!("sample_{k:04}/teapot.{name}.exr.key")))
            .expect("key")
    };
    ["specular_distant", "specular_local", "ptm"]
        .iter()
        .flat_map(|n| [key(0, n), key(1, n)])
        .collect()
}

/// Each sample's report gains the sphere EM and keeps the other layers.
fn assert_sphere_in_sample_reports(out: &std::path::Path) {
    for k in 0..2 {
        let sample = out.join(format!("sample_{k:04}"));
        assert!(sample.join("teapot.specular_sphere.exr").is_file());
        let report = json(&sample.join("report.json"));
        assert_eq!(
            layer_names(&report),
            [
                "teapot.specular_distant",
                "teapot.specular_local",
                "teapot.specular_sphere",
                "teapot.ptm"
            ],
            "{report}"
        );
        let sphere = &report["layers"][2];
        for psnr in ["least_squares", "forward_mapping", "static_em"] {
            assert!(
                sphere["psnr_db"][psnr]
                    .as_f64()
                    .is_some_and(|v| v.is_finite() && v > 5.0),
                "{psnr}: {sphere}"
            );
        }
        let renders: u64 = report["layers"]
            .as_array()
            .expect("layers")
            .iter()
            .filter_map(|l| l["probe_renders"].as_u64())
            .sum();
        assert_eq!(report["probe_renders"].as_u64(), Some(renders), "{report}");
    }
}

/// The summary has the sphere EM beside the others, with its baselines.
fn assert_sphere_in_summary(out: &std::path::Path, text: &str) {
    assert!(
        text.contains("teapot.specular_sphere") && text.contains("2 samples: LS"),
        "{text}"
    );
    let summary = json(&out.join("summary.json"));
    let sphere = &summary["teapot.specular_sphere"];
    assert_eq!(sphere["samples"].as_u64(), Some(2), "{summary}");
    assert!(
        sphere["forward_mapping_db_median"]
            .as_f64()
            .is_some_and(f64::is_finite)
    );
    assert!(
        sphere["static_em_db_median"]
            .as_f64()
            .is_some_and(f64::is_finite)
    );
    assert_eq!(
        summary["teapot.specular_distant"]["samples"].as_u64(),
        Some(2)
    );
}

/// The run that adds the sphere EM: the other 6 maps are skipped, said
/// before any work, and only the sphere EM of each sample is inferred.
fn assert_only_the_sphere_is_inferred(text: &str, stderr: &str) {
    assert!(
        stderr.contains("teapot.specular_distant 2/0")
            && stderr.contains("teapot.specular_sphere 0/2"),
        "{stderr}"
    );
    assert!(text.contains("6 maps already inferred"), "{text}");
    let inferred: Vec<&str> = text.lines().filter(|l| l.starts_with("sample")).collect();
    assert_eq!(inferred.len(), 2, "{text}");
    assert!(
        inferred
            .iter()
            .all(|l| l.contains("teapot.specular_sphere")),
        "{text}"
    );
}

#[test]
fn sphere_em_is_added_to_an_inferred_pem_without_redoing_its_maps() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(dir.path(), 2);
    let out = dir.path().join("infer");
    let traces = dir.path().join("trace");
    let base = [
        "infer",
        "--scene",
        &scene,
        "--size",
        "48x36",
        "--em-size",
        "8",
        "--spp",
        "2",
        "--out",
        out.to_str().expect("utf-8"),
        "--trace-dir",
        traces.to_str().expect("utf-8"),
    ];
    let run = |extra: &[&str]| {
        let o = engine(&[&base[..], extra].concat());
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{stderr}\n{stdout}");
        (stdout, stderr)
    };
    let (text, _) = run(&["--all"]);
    assert!(!text.contains("specular_sphere"), "{text}");
    let keys = map_keys(&out);

    // Adding the sphere EM infers it alone: the other maps keep their keys
    // and are skipped, and say so before any work.
    let (text, stderr) = run(&["--all", "--sphere"]);
    assert_only_the_sphere_is_inferred(&text, &stderr);
    assert_eq!(keys, map_keys(&out));
    assert_sphere_in_sample_reports(&out);
    assert_sphere_in_summary(&out, &text);

    // A third run has nothing left to do.
    let (text, _) = run(&["--all", "--sphere"]);
    assert!(text.contains("8 maps already inferred"), "{text}");

    // With --sample, every map of that sample is inferred, sphere included.
    let (text, _) = run(&["--sample", "1", "--sphere"]);
    assert_eq!(
        text.lines().filter(|l| l.starts_with("sample")).count(),
        4,
        "{text}"
    );
    let report = json(&out.join("report.json"));
    assert_eq!(report["sample"].as_u64(), Some(1));
    assert_eq!(layer_names(&report).len(), 4, "{report}");

    // A damaged sample report does not block the run: it is said and
    // started afresh, and holds every map inferred again.
    let bad = out.join("sample_0000/report.json");
    std::fs::write(&bad, "{ not json").expect("write");
    let (_, err) = run(&["--sample", "0", "--sphere"]);
    assert!(
        err.contains("sample_0000") && err.contains("starting it afresh"),
        "{err}"
    );
    let report = json(&bad);
    assert_eq!(layer_names(&report).len(), 4, "{report}");
}

#[test]
fn sample_out_of_range_fails_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = engine(&[
        "infer",
        "--sample",
        "1000",
        "--out",
        dir.path().to_str().expect("utf-8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("--sample 1000") && err.contains("0..253"),
        "{err}"
    );
    assert!(!err.contains("panicked"));
}

#[test]
fn em_size_must_be_a_power_of_two() {
    let o = engine(&["infer", "--sample", "0", "--em-size", "100"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("power of two"), "{err}");
}

#[test]
fn diffuse_texture_from_stacked_views() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("infer");
    let traces = dir.path().join("trace");
    let o = engine(&[
        "infer",
        "--diffuse",
        "floor",
        "--views",
        "0,60",
        "--size",
        "64x48",
        "--spp",
        "2",
        "--texture-size",
        "32",
        "--out",
        out.to_str().expect("utf-8"),
        "--trace-dir",
        traces.to_str().expect("utf-8"),
        "--validate",
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{}\n{stdout}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    assert!(out.join("floor.diffuse.exr").is_file());
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("diffuse_report.json")).expect("report"))
            .expect("JSON");
    let psnr = report["psnr_per_view_db"].as_array().expect("per view");
    assert_eq!(psnr.len(), 2);
    assert!(
        psnr.iter()
            .all(|p| p.as_f64().is_some_and(|v| v.is_finite() && v > 5.0)),
        "{report}"
    );
}

#[test]
fn diffuse_needs_a_diffuse_object() {
    let o = engine(&["infer", "--diffuse", "teapot"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("not diffuse"), "{err}");
    let o = engine(&["infer", "--diffuse", "nothing"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("no such object")
            && err.contains("its diffuse objects: floor, walls, ceiling"),
        "{err}"
    );
}

/// Rewrites `path` with pixel `pixel` of `layer`'s first channel set to NaN.
fn poison(path: &std::path::Path, layer: &str, pixel: usize, width: u32, height: u32) {
    use inference::trace::{Layer, TraceImage, output};
    let layers = output::read_exr(path).expect("read traced EXR");
    let layers = layers
        .into_iter()
        .map(|(name, channels)| {
            // Interleave in R, G, B, A (or Y) order, as the tracer writes.
            let order: Vec<&'static str> = ["R", "G", "B", "A", "Y"]
                .into_iter()
                .filter(|c| channels.iter().any(|(n, _)| n == c))
                .collect();
            let get = |c: &str| &channels.iter().find(|(n, _)| n == c).expect("channel").1;
            let n = order.len();
            let mut pixels = vec![0.0f32; (width * height) as usize * n];
            for (ci, c) in order.iter().enumerate() {
                for (p, v) in get(c).iter().enumerate() {
                    pixels[p * n + ci] = *v;
                }
            }
            if name == layer {
                pixels[pixel * n] = f32::NAN;
            }
            Layer {
                name,
                channels: order,
                pixels,
            }
        })
        .collect();
    let image = TraceImage {
        width,
        height,
        layers,
        rays: 0,
        elapsed: std::time::Duration::ZERO,
    };
    // As if the tracer itself had made the NaN: the file keeps a valid record
    // (a file altered behind the engine's back would just be traced again).
    let record = inference::key::read_record(path).expect("the trace's key record");
    output::write_exr(path, &image).expect("rewrite EXR");
    inference::key::write_record(path, &record.key).expect("record it");
}

#[test]
fn nan_in_a_traced_layer_names_file_layer_and_pixel() {
    let dir = tempfile::tempdir().expect("tempdir");
    let traces = dir.path().join("trace");
    let traces_s = traces.to_str().expect("utf-8");
    let o = engine(&[
        "trace", "--sample", "2", "--size", "48x36", "--spp", "2", "--out", traces_s,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The teapot sits in the middle of the frame.
    let pixel = 18 * 48 + 24;
    poison(
        &traces.join("sample_0002.exr"),
        "teapot.specular_distant",
        pixel,
        48,
        36,
    );
    let o = engine(&[
        "infer",
        "--sample",
        "2",
        "--size",
        "48x36",
        "--spp",
        "2",
        "--em-size",
        "8",
        "--out",
        dir.path().join("infer").to_str().expect("utf-8"),
        "--trace-dir",
        traces_s,
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "NaN accepted");
    assert!(!err.contains("panicked"), "{err}");
    for needle in [
        "sample_0002.exr",
        "teapot.specular_distant",
        &format!("pixel {pixel}"),
    ] {
        assert!(err.contains(needle), "error lacks {needle:?}: {err}");
    }
}
