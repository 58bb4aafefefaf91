//! `engine compile`: a compile farmed over shards gives the same maps (the same
//! files, byte for byte) and the same container (byte for byte) as one
//! process; the merge refuses to finish while a shard's samples are
//! missing; the shipped compiled scene still matches its inputs.

mod common;

use common::{output_text as text, run_engine, tiny_scene, traced_views};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

fn compile(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "compile",
        "--scene",
        scene.to_str().expect("utf-8"),
        "--size",
        "64x48",
        "--out",
        out.to_str().expect("utf-8"),
        "--validate",
    ];
    args.extend_from_slice(extra);
    run_engine(&args)
}

fn ok(o: Output) -> String {
    let log = text(&o);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("validation messages: 0"), "{log}");
    log
}

/// Every inferred map under `out/infer`, as (relative path → its bytes):
/// EXR blocks are written in order, so equal texels make equal files.
fn maps(out: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut found = BTreeMap::new();
    let infer = out.join("infer");
    for sample in std::fs::read_dir(&infer).expect("infer dir") {
        let sample = sample.expect("entry").path();
        if !sample.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&sample).expect("sample dir") {
            let file = file.expect("entry").path();
            if file.extension().is_some_and(|e| e == "exr") {
                found.insert(
                    file.strip_prefix(out).expect("under out").to_path_buf(),
                    std::fs::read(&file).expect("map bytes"),
                );
            }
        }
    }
    found
}

#[test]
fn a_sharded_compile_is_bit_identical_to_one_process() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = tiny_scene(dir.path());
    // 12 samples: two warm chains (0–9, 10–11), one per shard.
    let text_of_scene = std::fs::read_to_string(&scene).expect("scene");
    std::fs::write(
        &scene,
        text_of_scene.replacen("samples = 3", "samples = 12", 1),
    )
    .expect("write scene");
    let one = dir.path().join("one");
    let farm = dir.path().join("farm");

    ok(compile(&scene, &one, &[]));

    // Shard 1 alone: the merge names what is missing and writes nothing.
    let log = ok(compile(&scene, &farm, &["--shard", "1/2"]));
    assert!(log.contains("shard 1/2: 2 samples"), "{log}");
    let early = compile(&scene, &farm, &["--merge"]);
    assert!(!early.status.success(), "{}", text(&early));
    assert!(
        text(&early).contains("10 samples have no fresh maps yet (0, 1, 2, 3, 4, 5, …"),
        "{}",
        text(&early)
    );
    assert!(!farm.join("teapot.ptxc").exists());

    ok(compile(&scene, &farm, &["--shard", "0/2"]));
    ok(compile(&scene, &farm, &["--merge"]));

    let (a, b) = (maps(&one), maps(&farm));
    assert_eq!(a.len(), 36, "12 samples × 3 maps: {:?}", a.keys());
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (path, bytes) in &a {
        assert!(&b[path] == bytes, "{} differs", path.display());
    }
    let container = |d: &Path| std::fs::read(d.join("teapot.ptxc")).expect("container");
    assert!(container(&one) == container(&farm), "containers differ");
}

#[test]
fn bad_shards_fail_before_any_work() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = tiny_scene(dir.path());
    let out = dir.path().join("out");
    for bad in [&["--shard", "2/2"][..], &["--shard", "1/2", "--merge"]] {
        let o = compile(&scene, &out, bad);
        assert!(!o.status.success(), "{bad:?}: {}", text(&o));
    }
    assert!(!out.join("trace").exists(), "no work was done");
}

/// The compiled scene shipped in `assets/compiled/` is played only while
/// its keys match the inputs; this fails as soon as they no longer do (a
/// scene, tracer, solve or codec change): regenerate it with
/// `engine compile --scene teapot --ship assets/compiled/teapot` (and the
/// same for `glass`).
#[test]
fn the_shipped_compiled_scene_matches_its_inputs() {
    let o = run_engine(&["compile", "--scene", "teapot", "--check-shipped"]);
    let log = text(&o);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("teapot.ptxc: fresh"), "{log}");
    assert!(log.contains("floor.light.exr: fresh"), "{log}");
    // The glass scene's per-sample shell maps and room light maps (`engine
    // compile --scene glass --ship assets/compiled/glass`).
    let o = run_engine(&["compile", "--scene", "glass", "--check-shipped"]);
    let log = text(&o);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("room_shells.ptxc: fresh"), "{log}");
    assert!(log.contains("glass/room/floor.light.exr: fresh"), "{log}");
}

/// The tiny scene with `lines` after its `neighbour_weight` line, written
/// in `dir`; returns its path and the text without them.
fn tiny_scene_stacking(dir: &Path, lines: &str) -> (PathBuf, String) {
    let scene = tiny_scene(dir);
    let plain = std::fs::read_to_string(&scene).expect("scene");
    let weight = "neighbour_weight = 1.0";
    assert!(plain.contains(weight), "teapot.toml lacks {weight:?}");
    let edited = plain.replacen(weight, &format!("{weight}\n{lines}"), 1);
    std::fs::write(&scene, edited).expect("write scene");
    (scene, plain)
}

/// `neighbour_above_deg`: each sample's solves also stack a view traced
/// above it at its azimuth, which changes the maps; the same scene without
/// the line re-infers them (their keys differ) from the same sample traces.
#[test]
fn views_above_each_sample_are_traced_once_and_change_the_maps() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (scene, plain) = tiny_scene_stacking(dir.path(), "neighbour_above_deg = [15.0]");
    let out = dir.path().join("out");
    let log = ok(compile(&scene, &out, &[]));
    let views = traced_views(&out);
    let expected: Vec<String> = ["+0.000", "+1.000", "+2.000"]
        .map(|a| format!("view_az{a}_el+15.000.exr"))
        .to_vec();
    assert_eq!(views, expected, "{log}");
    let with_above = maps(&out);
    assert_eq!(with_above.len(), 9, "3 samples × 3 maps");

    std::fs::write(&scene, &plain).expect("write scene");
    let log = ok(compile(&scene, &out, &[]));
    let without = maps(&out);
    // Every map stacks the same views: the layered PEM's two and the PTM.
    let changed: Vec<_> = with_above
        .iter()
        .filter(|(p, bytes)| without.get(*p) != Some(*bytes))
        .map(|(p, _)| p.to_string_lossy().into_owned())
        .collect();
    assert_eq!(changed.len(), 9, "{changed:?}\n{log}");
}

/// `neighbour_above_spacing_deg`: views above on an azimuth grid, each
/// shared by the samples nearest it: the tiny orbit's 3 samples (0°, 1°,
/// 2°) on a 2° grid trace 2 views, not 3 (sample 1 ties and takes 2°).
/// Then `neighbour_above_weight` re-solves the maps from the same traces,
/// and changes them.
#[test]
fn shared_views_above_are_traced_once_per_grid_azimuth() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lines = "neighbour_above_deg = [15.0]\nneighbour_above_spacing_deg = 2.0";
    let (scene, _) = tiny_scene_stacking(dir.path(), lines);
    let out = dir.path().join("out");
    let log = ok(compile(&scene, &out, &[]));
    let grid = ["view_az+0.000_el+15.000.exr", "view_az+2.000_el+15.000.exr"];
    assert_eq!(traced_views(&out), grid, "{log}");
    let full = maps(&out);
    assert_eq!(full.len(), 9, "3 samples × 3 maps");
    assert!(log.contains("compile time of these maps:"), "{log}");

    let light = format!("{lines}\nneighbour_above_weight = 0.25");
    tiny_scene_stacking(dir.path(), &light);
    let log = ok(compile(&scene, &out, &[]));
    assert_eq!(traced_views(&out), grid, "no new views: {log}");
    let changed: Vec<_> = maps(&out)
        .into_iter()
        .filter(|(p, bytes)| full.get(p) != Some(bytes))
        .map(|(p, _)| p.to_string_lossy().into_owned())
        .collect();
    assert_eq!(changed.len(), 9, "{changed:?}\n{log}");
}
