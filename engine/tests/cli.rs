//! The `engine` binary end to end: a validated run writes frames and
//! perf.json; bad input gives a one-line error naming what was wrong, a
//! non-zero exit and never a panic.

use std::path::Path;
use std::process::{Command, Output};

fn engine(args: &[&str], envs: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_engine"));
    cmd.args(args);
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.output().expect("run engine")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A failed run: non-zero exit, an `error:` line containing every needle,
/// and no panic.
fn assert_clean_failure(o: &Output, needles: &[&str]) {
    let err = stderr(o);
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

#[test]
fn validated_run_writes_frames_and_perf_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().to_str().expect("utf-8 temp path");
    let o = engine(
        &[
            "--scene",
            "teapot",
            "--frames",
            "3",
            "--size",
            "96x64",
            "--warmup",
            "1",
            "--out",
            out,
            "--validate",
            "--exr",
            "--mode",
            "static-em",
        ],
        &[],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "stderr:\n{}", stderr(&o));
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    for i in 0..3 {
        assert!(dir.path().join(format!("frame_{i:04}.png")).is_file());
        assert!(dir.path().join(format!("frame_{i:04}.exr")).is_file());
    }
    let perf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("perf.json")).expect("perf.json"))
            .expect("valid JSON");
    assert_eq!(perf["size"], serde_json::json!([96, 64]));
    assert_eq!(perf["frames"], 3);
    assert!(perf["device"].as_str().is_some_and(|d| !d.is_empty()));
    assert!(perf["frame_ms_median"].as_f64().is_some_and(|v| v > 0.0));
    let (median, p95, max) = (
        perf["frame_ms_median"].as_f64(),
        perf["frame_ms_p95"].as_f64(),
        perf["frame_ms_max"].as_f64(),
    );
    assert!(
        p95 >= median && p95 <= max,
        "p95 {p95:?} against median {median:?} and max {max:?}"
    );
    // No maps to decode in this mode: no worker times, said as null.
    assert_eq!(perf["cpu"]["ahead_decodes"], 0);
    assert!(perf["cpu"]["ahead_decode_ms_p95"].is_null());
    assert!(perf["cpu"]["texgen_ms_median"].as_f64().is_some());
    assert!(perf["cpu"]["upload_ms_median"].as_f64().is_some());
    let submit = perf["cpu"]["submit_to_fence_ms_median"].as_f64();
    let outside = perf["cpu"]["outside_passes_ms_median"].as_f64();
    assert!(
        outside.zip(submit).is_some_and(|(o, s)| o >= 0.0 && o <= s),
        "{outside:?} outside the passes of {submit:?}"
    );
    let passes = perf["passes"].as_array().expect("passes");
    let names: Vec<&str> = passes.iter().filter_map(|p| p["name"].as_str()).collect();
    assert_eq!(names, ["room", "mirror", "readback"]);
    let room = &passes[0];
    // The room covers the whole frame at least once.
    assert!(
        room["fragment_invocations"]
            .as_u64()
            .is_some_and(|n| n >= 96 * 64),
        "{room}"
    );
    assert!(room["gpu_ms_median"].as_f64().is_some_and(|v| v > 0.0));
    assert!(room["gpu_ms_max"].as_f64() >= room["gpu_ms_median"].as_f64());
}

#[test]
fn help_documents_every_flag() {
    let o = engine(&["--help"], &[]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    for flag in [
        "--scene",
        "--frames",
        "--size",
        "--out",
        "--validate",
        "--device",
        "--mode",
    ] {
        assert!(text.contains(flag), "--help lacks {flag}");
    }
    // Every built-in scene is named where --scene is described, in every
    // command that takes one.
    for cmd in [&["--help"][..], &["bench", "--help"], &["eval", "--help"]] {
        let o = engine(cmd, &[]);
        let text = String::from_utf8_lossy(&o.stdout);
        for (name, _) in inference::scene::SHIPPED {
            assert!(
                text.contains(name),
                "{cmd:?} lacks the built-in scene {name}"
            );
        }
    }
}

#[test]
fn unknown_scene_name() {
    let o = engine(&["--scene", "no-such-scene"], &[]);
    assert_clean_failure(&o, &["no-such-scene"]);
}

#[test]
fn malformed_scene_file_names_file_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("broken.toml");
    std::fs::write(&path, "[camera]\nfov_y_deg = = 40\n").expect("write");
    let o = engine(&["--scene", path.to_str().expect("utf-8")], &[]);
    assert_clean_failure(&o, &["broken.toml", "line 2"]);
}

fn scene_with_obj(dir: &Path, obj: &str) -> std::path::PathBuf {
    let text = inference::scene::shipped("teapot").expect("built-in teapot");
    std::fs::write(dir.join("mesh.obj"), obj).expect("write obj");
    // Swap the generated teapot for the OBJ next to the scene file.
    let obj_line = format!("mesh = {{ obj = \"{}\" }}", dir.join("mesh.obj").display());
    let patched: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with("mesh = { generator") {
                obj_line.clone()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(
        patched.contains(&obj_line),
        "teapot scene uses the generator"
    );
    let patched = patched.join("\n");
    let path = dir.join("scene.toml");
    std::fs::write(&path, patched).expect("write scene");
    path
}

#[test]
fn obj_with_nan_coordinates() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = scene_with_obj(dir.path(), "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
    let o = engine(
        &["--scene", scene.to_str().expect("utf-8"), "--frames", "1"],
        &[],
    );
    assert_clean_failure(&o, &["mesh.obj", "line 3"]);
}

#[test]
fn obj_with_degenerate_triangle() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = scene_with_obj(dir.path(), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    let o = engine(
        &["--scene", scene.to_str().expect("utf-8"), "--frames", "1"],
        &[],
    );
    assert_clean_failure(&o, &["mesh.obj", "zero-area"]);
}

#[test]
fn unwritable_output_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"").expect("write");
    // A folder cannot be made under a regular file (root ignores modes).
    let out = file.join("frames");
    let o = engine(
        &["--out", out.to_str().expect("utf-8"), "--frames", "1"],
        &[],
    );
    assert_clean_failure(&o, &["output folder", "a-file"]);
}

#[test]
fn no_vulkan_driver() {
    let dir = tempfile::tempdir().expect("tempdir");
    let icd = dir.path().join("no-such-icd.json");
    let icd = icd.to_str().expect("utf-8");
    let out = dir.path().join("out");
    let o = engine(
        &[
            "--frames",
            "1",
            "--size",
            "8x8",
            "--no-capture",
            "--mode",
            "static-em",
            "--out",
            out.to_str().expect("utf-8"),
        ],
        &[("VK_DRIVER_FILES", icd), ("VK_ICD_FILENAMES", icd)],
    );
    assert_clean_failure(&o, &["Vulkan"]);
}

#[test]
fn unknown_device_name_lists_available() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let o = engine(
        &[
            "--device",
            "no-such-gpu",
            "--frames",
            "1",
            "--no-capture",
            "--out",
            out.to_str().expect("utf-8"),
        ],
        &[],
    );
    assert_clean_failure(&o, &["no-such-gpu", "llvmpipe"]);
}

#[test]
fn bad_size_is_rejected_by_the_parser() {
    let o = engine(&["--size", "0x480"], &[]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("WIDTHxHEIGHT"));
}

#[test]
fn bad_angles_and_tau_fail_before_any_work() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let out_s = out.to_str().expect("utf-8");
    for (args, needle) in [
        (
            vec!["eval", "--elevation", "95", "--out", out_s],
            "strictly between -90 and 90",
        ),
        (
            vec!["eval", "--elevation", "10,nan", "--out", out_s],
            "strictly between -90 and 90",
        ),
        (
            vec![
                "trace",
                "--view-angle",
                "10",
                "--elevation",
                "120",
                "--out",
                out_s,
            ],
            "strictly between -90 and 90",
        ),
        (
            vec!["trace", "--view-angle", "inf", "--out", out_s],
            "an angle in degrees",
        ),
        (
            vec!["--scene", "glass", "--tau", "0", "--out", out_s],
            "0.1..=1000.0 subpixels",
        ),
        (
            vec!["infer", "--sample", "0", "--eps-f", "nan", "--out", out_s],
            "a finite weight >= 0",
        ),
        (
            vec!["bench", "--frames", "268435456", "--out", out_s],
            "1..=100000",
        ),
        (
            vec!["bench", "--warmup", "4294967295", "--out", out_s],
            "0..=100000",
        ),
    ] {
        let o = engine(&args, &[]);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        // Refused by the parser: nothing traced, compiled or written.
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// Mistakes found before any tracing, compiling or writing: flags that
/// cannot go together or out of range, a report whose folder is missing,
/// a scene placement cannot refine.
#[test]
fn mistakes_are_refused_before_any_work_and_leave_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let out_s = out.to_str().expect("utf-8");
    let json = dir.path().join("missing").join("r.json");
    let json_s = json.to_str().expect("utf-8");
    for (args, needles) in [
        (
            vec![
                "trace",
                "--sample",
                "0",
                "--elevation",
                "10",
                "--out",
                out_s,
            ],
            vec!["--elevation", "needs --view-angle"],
        ),
        (
            vec!["relight", "--grid", "0x0", "--out", out_s],
            vec!["RINGSxAZIMUTHS", "azimuths 1 to 128"],
        ),
        (
            vec!["relight", "--ratio", "0", "--out", out_s],
            vec!["--ratio 0", "compression ratio"],
        ),
        // 1:1 is no compression: relight and encode refuse it alike.
        (
            vec!["relight", "--ratio", "1", "--out", out_s],
            vec!["--ratio 1: expected a compression ratio above 1 and at most 100,000"],
        ),
        (
            vec!["encode", "--ratio", "1", "--out", json_s],
            vec!["--ratio 1: expected a compression ratio above 1 and at most 100,000"],
        ),
        (
            vec!["relight", "--json", json_s, "--out", out_s],
            vec!["r.json", "does not exist"],
        ),
        (
            vec!["encode", "--bytes", "0", "--out", json_s],
            vec!["--bytes 0", "above 0 bytes"],
        ),
        (
            vec!["encode", "--out", json_s],
            vec!["r.json", "does not exist"],
        ),
        (
            vec!["place", "--scene", "teapot", "--data", out_s],
            // A built-in scene is named as one: no repository path.
            vec![
                "built-in scene 'teapot': orbit.ring_line_every = 2",
                "rings = 1",
            ],
        ),
        (
            vec![
                "trace",
                "--sample",
                "0",
                "--threads",
                "100000",
                "--out",
                out_s,
            ],
            vec!["1 to 256"],
        ),
        (vec!["eval", "--spp", "0", "--out", out_s], vec!["1..=4096"]),
        (
            vec![
                "place",
                "--scene",
                "brass",
                "--target-db",
                "nan",
                "--data",
                out_s,
            ],
            vec!["'--target-db <TARGET_DB>'", "a finite PSNR"],
        ),
        // A negative number reaches its flag's parser, which names the flag.
        (
            vec!["bench", "--frames", "-1", "--out", out_s],
            vec!["'--frames <FRAMES>'", "1..=100000"],
        ),
        (
            vec!["trace", "--sample", "-1", "--out", out_s],
            vec!["'--sample <SAMPLE>'", "0..4096"],
        ),
    ] {
        let o = engine(&args, &[]);
        let err = stderr(&o);
        assert!(
            !o.status.success() && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        for n in needles {
            assert!(err.contains(n), "{args:?} lacks {n:?}: {err}");
        }
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// "lavapipe", the default the help names, finds Mesa's llvmpipe device.
#[test]
fn the_device_the_help_names_is_found() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let out_s = out.to_str().expect("utf-8");
    let args = [
        "--device",
        "lavapipe",
        "--frames",
        "1",
        "--size",
        "96x64",
        "--warmup",
        "1",
        "--mode",
        "static-em",
        "--no-capture",
        "--validate",
        "--out",
        out_s,
    ];
    let o = engine(&args, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
}

/// A scene with neither a reflector's maps nor glass has nothing to bench:
/// said before anything is compiled.
#[test]
fn bench_without_reflectors_or_glass_says_so_first() {
    let dir = tempfile::tempdir().expect("tempdir");
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes/glass.toml");
    let text = std::fs::read_to_string(source).expect("glass.toml");
    let plain = text
        .split("[objects.glass]")
        .next()
        .expect("text")
        .replace("material = \"glass\"", "material = \"walls\"");
    let scene = dir.path().join("plain.toml");
    std::fs::write(&scene, plain).expect("write scene");
    let out = dir.path().join("out");
    let o = engine(
        &[
            "bench",
            "--scene",
            scene.to_str().expect("utf-8 path"),
            "--out",
            out.to_str().expect("utf-8 path"),
        ],
        &[],
    );
    assert_clean_failure(&o, &["plain.toml", "nothing to bench"]);
    assert!(!stderr(&o).contains("light map"), "{}", stderr(&o));
}
