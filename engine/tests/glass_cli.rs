//! `engine --scene glass` end to end, on a small copy of the glass scene:
//! the first run traces the room shell map and plays hybrid frames (the
//! default mode for glass) with validation clean; the second compiles
//! nothing; a bad τ and hybrid without glass fail cleanly.

use std::path::Path;
use std::process::{Command, Output};

fn engine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

/// glass.toml with a 16² shell map and a coarse teapot, in `dir`.
fn small_glass(dir: &Path) -> String {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes/glass.toml");
    let mut text = std::fs::read_to_string(source).expect("glass.toml");
    for (from, to) in [
        ("resolution = 256", "resolution = 16"),
        ("segments = 25 }", "segments = 6 }"),
    ] {
        assert!(text.contains(from), "glass.toml lacks {from:?}");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join("small_glass.toml");
    std::fs::write(&path, text).expect("write scene");
    path.to_str().expect("utf-8 path").to_owned()
}

fn run(scene: &str, out: &Path, extra: &[&str]) -> Output {
    let out = out.to_str().expect("utf-8 path");
    let mut args = vec![
        "--scene", scene, "--frames", "2", "--size", "96x64", "--warmup", "1",
    ];
    args.extend(["--out", out, "--validate"]);
    args.extend(extra);
    engine(&args)
}

#[test]
fn glass_compiles_its_shell_once_and_plays_hybrid() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = small_glass(dir.path());
    let out = dir.path().join("out");
    let first = run(&scene, &out, &[]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&first.stdout),
        String::from_utf8_lossy(&first.stderr),
    );
    assert!(first.status.success(), "stderr:\n{stderr}");
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    assert!(stderr.contains("traced the room shell map"), "{stderr}");
    assert!(out.join("glass/room_shell.bin").is_file());
    let perf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("perf.json")).expect("perf.json"))
            .expect("valid JSON");
    assert_eq!(perf["mode"], "Hybrid");
    let names: Vec<&str> = perf["passes"]
        .as_array()
        .expect("passes")
        .iter()
        .filter_map(|p| p["name"].as_str())
        .collect();
    assert_eq!(names, ["room", "glass", "readback"]);

    // Cached: nothing traced again; the baseline plays from the same map.
    let second = run(&scene, &out, &["--mode", "static-em", "--tau", "10"]);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(second.status.success(), "stderr:\n{stderr}");
    assert!(!stderr.contains("traced the room shell map"), "{stderr}");

    let bad_tau = run(&scene, &out, &["--tau", "0"]);
    let stderr = String::from_utf8_lossy(&bad_tau.stderr);
    assert!(
        !bad_tau.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("error:") && l.contains("--tau 0")),
        "{stderr}"
    );
}

#[test]
fn hybrid_without_glass_fails_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = run("teapot", &dir.path().join("out"), &["--mode", "hybrid"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    let line = stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_default();
    assert!(line.contains("[objects.glass]"), "{stderr}");
}
