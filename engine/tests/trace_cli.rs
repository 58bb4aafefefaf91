//! `engine trace` end to end: a tiny trace writes the layered EXR, the PNG and the
//! throughput line; bad input gives one `error:` line, a non-zero exit and no files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn engine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

fn assert_clean_failure(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "expected failure, stderr:\n{err}");
    assert!(!err.contains("panicked"), "panicked:\n{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no error line in:\n{err}"));
    for n in needles {
        assert!(line.contains(n), "error line lacks {n:?}: {line}");
    }
}

/// Files in `dir` (none when it does not exist).
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != ".pem-engine")
        .collect();
    names.sort();
    names
}

/// The teapot scene as a 1D orbit with one line replaced, written into `dir`.
fn patched_teapot(dir: &Path, from: &str, to: &str) -> PathBuf {
    let text = inference::scene::shipped("teapot").expect("built-in teapot");
    let text = inference::scene::shipped::without_views_above(text);
    assert!(text.contains(from), "teapot.toml has {from:?}");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write scene");
    path
}

#[test]
fn tiny_trace_writes_layers_png_and_throughput() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("trace");
    let o = engine(&[
        "trace",
        "--scene",
        "teapot",
        "--sample",
        "3",
        "--size",
        "32x24",
        "--spp",
        "2",
        "--threads",
        "2",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "stderr:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let last = stdout.lines().last().unwrap_or_default();
    let rest = last
        .strip_prefix("rays: ")
        .expect("last line: rays: N, Mrays/s: X");
    let (rays, mrays) = rest.split_once(", Mrays/s: ").expect("Mrays/s");
    assert!(
        rays.parse::<u64>().is_ok_and(|n| n >= 32 * 24 * 2),
        "{last}"
    );
    assert!(mrays.parse::<f64>().is_ok_and(|v| v > 0.0), "{last}");

    assert_eq!(
        files(&out),
        ["sample_0003.exr", "sample_0003.exr.key", "sample_0003.png"]
    );
    let layers = inference::trace::output::read_exr(&out.join("sample_0003.exr")).expect("EXR");
    let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    for want in [
        "beauty",
        "teapot.mask",
        "teapot.fresnel",
        "teapot.specular_distant",
        "teapot.specular_local",
        "floor.mask",
        "floor.diffuse",
        "walls.diffuse",
        "ceiling.diffuse",
        "light.mask",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    assert!(!names.contains(&"teapot.diffuse"));
    for (name, channels) in &layers {
        for (c, values) in channels {
            assert_eq!(values.len(), 32 * 24, "{name}.{c}");
            assert!(values.iter().all(|v| v.is_finite()), "{name}.{c}");
        }
    }
}

#[test]
fn sample_out_of_range_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("trace");
    let o = engine(&[
        "trace",
        "--sample",
        "253",
        "--size",
        "8x8",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_clean_failure(&o, &["sample 253", "0..253"]);
    assert!(files(&out).is_empty());
}

#[test]
fn zero_area_light_names_the_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = patched_teapot(
        dir.path(),
        "edge_v = [0.0, 0.0, 1.5]",
        "edge_v = [0.0, 0.0, 0.0]",
    );
    let out = dir.path().join("trace");
    let o = engine(&[
        "trace",
        "--scene",
        scene.to_str().expect("utf-8"),
        "--sample",
        "0",
        "--size",
        "8x8",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_clean_failure(&o, &["scene.toml", "lights", "zero area"]);
    assert!(files(&out).is_empty());
}

#[test]
fn unknown_material_kind_names_the_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = patched_teapot(dir.path(), "kind = \"mirror\"", "kind = \"velvet\"");
    let out = dir.path().join("trace");
    let o = engine(&[
        "trace",
        "--scene",
        scene.to_str().expect("utf-8"),
        "--sample",
        "0",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    // toml's message spans lines: the first names file and line, a later one the value.
    assert_clean_failure(&o, &["scene.toml", "line"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("unknown variant `velvet`"), "{err}");
    assert!(files(&out).is_empty());
}

#[test]
fn unwritable_output_folder_fails_before_tracing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"").expect("write");
    let out = file.join("trace");
    let o = engine(&[
        "trace",
        "--sample",
        "0",
        "--size",
        "8x8",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_clean_failure(&o, &["output folder", "a-file"]);
    assert_eq!(files(dir.path()), ["a-file"]);
}

#[test]
fn all_skips_samples_traced_with_the_same_inputs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = patched_teapot(dir.path(), "samples = 100", "samples = 3");
    let out = dir.path().join("trace");
    let args = |spp: &'static str| {
        [
            "trace",
            "--scene",
            scene.to_str().expect("utf-8"),
            "--all",
            "--size",
            "8x6",
            "--spp",
            spp,
            "--out",
            out.to_str().expect("utf-8"),
        ]
        .map(str::to_owned)
    };
    let run = |spp| {
        let o = Command::new(env!("CARGO_BIN_EXE_engine"))
            .args(args(spp))
            .output()
            .expect("run engine");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let first = run("1");
    assert_eq!(first.matches(".exr:").count(), 3, "{first}");
    assert_eq!(files(&out).len(), 9);
    let again = run("1");
    assert!(again.contains("3 samples already traced"), "{again}");
    assert!(again.ends_with("rays: 0, Mrays/s: 0.00\n"), "{again}");
    // A different input re-traces everything.
    let changed = run("2");
    assert_eq!(changed.matches(".exr:").count(), 3, "{changed}");
}

#[test]
fn free_view_keeps_its_angles_in_the_file_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("trace");
    let o = engine(&[
        "trace",
        "--view-angle",
        "-12.5",
        "--elevation",
        "20",
        "--size",
        "8x6",
        "--spp",
        "1",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        files(&out),
        [
            "view_az-12.500_el+20.000.exr",
            "view_az-12.500_el+20.000.exr.key",
            "view_az-12.500_el+20.000.png"
        ]
    );
}

#[test]
fn zero_samples_per_pixel_is_rejected_before_any_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("trace");
    let o = engine(&[
        "trace",
        "--sample",
        "0",
        "--spp",
        "0",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_clean_failure(&o, &["spp", "got 0"]);
    assert!(
        !out.exists(),
        "no output folder for a run that cannot start"
    );
}
