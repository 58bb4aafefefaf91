//! The glass CLI tests' helpers: small copies of the shipped glass
//! scenes, `engine` runs that must be validation-clean, and eval rows.

use super::run_engine as engine;
use std::path::Path;
use std::process::Output;

/// The shipped scene `name` with a 16² shell map, a coarse glass teapot
/// and `edits`, written into `dir`; its path.
pub fn small_scene(dir: &Path, name: &str, edits: &[(&str, &str)]) -> String {
    let source =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../assets/scenes/{name}.toml"));
    let mut text = std::fs::read_to_string(source).expect("shipped scene");
    let small = [
        ("resolution = 256", "resolution = 16"),
        ("segments = 25 }", "segments = 6 }"),
    ];
    for (from, to) in small.iter().chain(edits) {
        assert!(text.contains(from), "{name}.toml lacks {from:?}");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join(format!("small_{name}.toml"));
    std::fs::write(&path, text).expect("write scene");
    path.to_str().expect("utf-8 path").to_owned()
}

/// `engine compile` of `scene` into `out` at 96×64, probes validated.
pub fn compile(scene: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["compile", "--scene", scene, "--size", "96x64", "--validate"];
    args.extend(["--out", out.to_str().expect("utf-8 path")]);
    args.extend(extra);
    engine(&args)
}

/// `run` that must succeed with the validation layer silent; its stderr.
pub fn run_clean(scene: &str, out: &Path, extra: &[&str]) -> String {
    let o = run(scene, out, extra);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert!(o.status.success(), "stderr:\n{stderr}");
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    stderr
}

pub fn run(scene: &str, out: &Path, extra: &[&str]) -> Output {
    let out = out.to_str().expect("utf-8 path");
    let mut args = vec![
        "--scene", scene, "--frames", "2", "--size", "96x64", "--warmup", "1",
    ];
    args.extend(["--out", out, "--validate"]);
    args.extend(extra);
    engine(&args)
}

/// `engine eval` of `rows` (labels, comma-separated) on the compiled
/// `out` (small frames, one view per kind), its `eval.json`.
pub fn eval_hybrid_rows(scene: &str, out: &Path, eval_out: &Path, rows: &str) -> serde_json::Value {
    let o = engine(&[
        "eval",
        "--scene",
        scene,
        "--data",
        out.to_str().expect("utf-8"),
        "--out",
        eval_out.to_str().expect("utf-8"),
        "--size",
        "96x64",
        "--views",
        "1",
        "--spp",
        "2",
        "--repeats",
        "1",
        "--elevation",
        "10",
        "--validate",
        "--rows",
        rows,
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "stderr:\n{stderr}");
    serde_json::from_slice(&std::fs::read(eval_out.join("eval.json")).expect("eval.json"))
        .expect("valid JSON")
}

/// The row labelled `label` of `eval`.
pub fn eval_row<'a>(eval: &'a serde_json::Value, label: &str) -> &'a serde_json::Value {
    eval["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .find(|r| r["settings"]["label"] == label)
        .unwrap_or_else(|| panic!("no row {label}: {eval}"))
}
