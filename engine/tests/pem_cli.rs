//! The main job end to end on a tiny teapot scene (3 viewpoint samples,
//! 16² maps): the first run compiles what is missing (trace, infer,
//! encode) and plays layered PEMs; the second starts playing at once; every
//! mode and knob plays with validation on.

mod common;

use common::{output_text as text, tiny_scene};
use std::path::Path;
use std::process::{Command, Output};

fn engine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

fn play(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "--scene",
        scene.to_str().expect("utf-8"),
        "--size",
        "64x48",
        "--frames",
        "5",
        "--warmup",
        "1",
        "--out",
        out.to_str().expect("utf-8"),
        "--validate",
    ];
    args.extend_from_slice(extra);
    engine(&args)
}

fn pass_names(out: &Path) -> Vec<String> {
    let perf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("perf.json")).expect("perf.json"))
            .expect("JSON");
    perf["passes"]
        .as_array()
        .expect("passes")
        .iter()
        .filter_map(|p| p["name"].as_str().map(String::from))
        .collect()
}

/// `--score 3`: the first, middle and last of the 5 frames, as written,
/// against their traced views; the references are traced once. Refused
/// with `--no-capture` or `--light-path` before anything runs; a run
/// without `--score` removes the scores of an earlier one.
fn assert_path_is_scored(scene: &Path, out: &Path) {
    for (flags, needle) in [
        (["--no-capture", "--no-video"], "--score with --no-capture"),
        (["--light-path", "bulb"], "--score with --light-path"),
    ] {
        let refused = play(scene, out, &[&["--score", "3"][..], &flags].concat());
        assert!(!refused.status.success());
        assert!(text(&refused).contains(needle), "{}", text(&refused));
    }

    let first = play(scene, out, &["--score", "3", "--no-video"]);
    assert!(first.status.success(), "{}", text(&first));
    assert!(
        text(&first).contains("references: 3 traced, 0 from the cache"),
        "{}",
        text(&first)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("score.json")).expect("score.json"))
            .expect("JSON");
    let frames = json["frames"].as_array().expect("frames");
    let field = |f: &serde_json::Value, k: &str| f[k].as_f64().expect(k);
    let picked: Vec<f64> = frames.iter().map(|f| field(f, "frame")).collect();
    assert_eq!(picked, [0.0, 2.0, 4.0]);
    assert_eq!(frames[0]["kind"], "on a sample");
    assert_eq!(frames[2]["kind"], "above the orbit");
    assert!(field(&frames[2], "elevation_deg") > 19.0);
    // The tiny scene's 16² maps at 64x48 score 28.0 dB on the orbit and
    // 21.6 dB 20° above it (no rings); frame 0 scored against the 20°
    // view's reference reads 14.1 dB.
    for (f, lowest) in frames.iter().zip([24.0, 24.0, 18.0]) {
        let (db, flip) = (field(f, "psnr_frame_db"), field(f, "flip_frame"));
        assert!((lowest..45.0).contains(&db), "{f}");
        assert!(flip > 0.0 && flip < 0.3, "{f}");
    }
    let picture = image::open(out.join("score.png")).expect("score.png");
    assert_eq!((picture.width(), picture.height()), (3 * 64, 48));

    let again = play(scene, out, &["--score", "3", "--no-video"]);
    assert!(again.status.success(), "{}", text(&again));
    assert!(
        text(&again).contains("references: 0 traced, 3 from the cache"),
        "{}",
        text(&again)
    );

    // A run that does not score leaves no scores of other frames behind.
    let unscored = play(scene, out, &["--no-video"]);
    assert!(unscored.status.success(), "{}", text(&unscored));
    assert!(!out.join("score.json").exists() && !out.join("score.png").exists());
}

/// The first run traces, infers and encodes what is missing, then plays
/// deferred layered PEMs.
fn assert_first_run_compiles(scene: &Path, out: &Path) {
    let first = play(scene, out, &[]);
    assert!(first.status.success(), "{}", text(&first));
    let log = text(&first);
    assert!(log.contains("validation messages: 0"), "{log}");
    assert!(log.contains("tracing and inferring"), "{log}");
    assert!(out.join("teapot.ptxc").is_file(), "container compiled");
    for k in 0..3 {
        assert!(
            out.join(format!("infer/sample_{k:04}/teapot.specular_local.exr"))
                .is_file()
        );
    }
    for i in 0..5 {
        assert!(out.join(format!("frame_{i:04}.png")).is_file());
    }
    // Deferred by default: the reflector rasterized once into lookups, one
    // composite over the covered pixels; maps decoded straight into the
    // slots the composite samples (lavapipe samples host-written arrays),
    // so no upload pass.
    let names = pass_names(out);
    for pass in ["room", "pem_gbuffer", "pem_composite", "readback"] {
        assert!(names.iter().any(|n| n == pass), "{pass} missing: {names:?}");
    }
    for pass in ["pem_blend", "upload"] {
        assert!(!names.iter().any(|n| n == pass), "{names:?}");
    }
    // The decode worker's own times, per map, while the frames rendered.
    let perf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("perf.json")).expect("perf.json"))
            .expect("JSON");
    let cpu = &perf["cpu"];
    let (p50, p95) = (
        cpu["ahead_decode_ms_p50"].as_f64(),
        cpu["ahead_decode_ms_p95"].as_f64(),
    );
    assert!(
        cpu["ahead_decodes"].as_u64().is_some_and(|n| n > 0),
        "{cpu}"
    );
    assert!(
        p50.zip(p95).is_some_and(|(a, b)| 0.0 < a && a <= b),
        "{cpu}"
    );
}

/// An edited scene (the light's colour) is never played from old maps:
/// the run says what changed, traces, infers and encodes again.
fn assert_edited_scene_recompiles(scene: &Path, out: &Path) {
    let text_of_scene = std::fs::read_to_string(scene).expect("scene");
    let edited = text_of_scene.replacen(
        "radiance = [12.0, 11.5, 10.5]",
        "radiance = [12.0, 11.5, 4.0]",
        1,
    );
    assert_ne!(edited, text_of_scene, "the tiny scene has the light");
    std::fs::write(scene, edited).expect("edit scene");
    let stale = play(scene, out, &["--no-capture"]);
    let log = text(&stale);
    assert!(stale.status.success(), "{log}");
    assert!(
        log.contains("lights, materials changed"),
        "not said what changed: {log}"
    );
    assert!(log.contains("ratio"), "not re-encoded: {log}");
}

/// The bench measures every variant at the same views (maps compiled above).
fn assert_bench_rows(scene: &Path, out: &Path) {
    let o = engine(&[
        "bench",
        "--scene",
        scene.to_str().expect("utf-8"),
        "--size",
        "64x48",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--elevation",
        "7.5",
        "--out",
        out.to_str().expect("utf-8"),
        "--validate",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let bench: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("bench.json")).expect("bench.json"))
            .expect("JSON");
    // The views where asked, said in the report and the table.
    assert_eq!(bench["elevation_deg"].as_f64(), Some(7.5), "{bench}");
    assert!(text(&o).contains("at +7.5°"), "{}", text(&o));
    let rows = bench["rows"].as_array().expect("rows");
    let names: Vec<&str> = rows.iter().filter_map(|r| r["name"].as_str()).collect();
    for v in [
        "bare",
        "static-em",
        "default",
        "default, analytic room",
        "multipass",
        "default, decoding",
    ] {
        assert!(names.contains(&v), "{v} missing: {names:?}");
    }
    assert!(
        rows.iter()
            .all(|r| r["frame_ms_median"].as_f64().is_some_and(|v| v > 0.0))
    );
    // Decoding straight into the slots (lavapipe samples host-written
    // arrays) needs no upload pass; the staging row has one.
    let uploads = |name: &str| {
        let row = rows.iter().find(|r| r["name"] == name).expect(name);
        let passes = row["report"]["passes"].as_array().expect("passes");
        passes.iter().any(|p| p["name"] == "upload")
    };
    assert!(!uploads("default, decoding"), "{bench}");
    assert!(uploads("default, decoding, staging uploads"), "{bench}");
    // The two room passes, compared in the report and printed.
    let room = &bench["room_pass"];
    let (i, a, r) = (
        room["inferred_ms"].as_f64().unwrap_or(-1.0),
        room["analytic_ms"].as_f64().unwrap_or(-1.0),
        room["ratio"].as_f64().unwrap_or(-1.0),
    );
    assert!(i > 0.0 && a > 0.0 && (r - i / a).abs() < 1e-9, "{room}");
    assert!(text(&o).contains("room pass: inferred"), "{}", text(&o));
    // Each row's passes printed with their device times: the default's
    // three passes on its own line.
    let printed = text(&o);
    let default_line = printed
        .lines()
        .skip_while(|l| !l.starts_with("device ms per pass"))
        .find(|l| l.starts_with("default ") && l.contains("| outside"))
        .unwrap_or_else(|| panic!("no pass line for the default row: {printed}"));
    for pass in ["pem_gbuffer", "room", "pem_composite"] {
        assert!(default_line.contains(&format!("{pass} ")), "{default_line}");
    }
    // The same as a picture: a bar per row, named at the table's end.
    assert!(
        printed
            .lines()
            .any(|l| l.starts_with("wrote ") && l.ends_with("bench.png")),
        "{printed}"
    );
    let chart = image::open(out.join("bench.png")).expect("bench.png");
    assert!(
        chart.height() >= 120 + 34 * rows.len() as u32,
        "{}",
        chart.height()
    );
}

/// Every mode and knob plays cleanly (sphere PEMs are inferred on first
/// use; the edge filter runs its passes only when asked for); each mode's frame between samples matches its golden image (the
/// goldens hold the analytic room: the reflectors are what they test;
/// the inferred room has its own test, room_maps.rs).
fn assert_every_mode_plays(scene: &Path, out: &Path) {
    for (mode, golden) in [
        ("layered-pem", "tiny_layered_pem"),
        ("sphere-pem", "tiny_sphere_pem"),
        ("ptm", "tiny_ptm"),
    ] {
        let o = play(scene, out, &["--mode", mode, "--room", "analytic"]);
        assert!(o.status.success(), "{mode}: {}", text(&o));
        let (w, h, pixels) = engine::capture::read_png(&out.join("frame_0001.png")).expect("frame");
        common::assert_matches_golden(golden, w, h, &pixels, 45.0);
    }
    for extra in [
        &["--mode", "trace", "--trace-spp", "1"][..],
        &["--mode", "static-em"],
        &["--no-blend", "--distant-only"],
        &["--maps", "exr", "--filtering", "nearest", "--em-size", "4"],
        &["--spacing", "2", "--filtering", "bilinear"],
        &["--edge-filter"],
    ] {
        let mut args = vec!["--no-capture"];
        args.extend_from_slice(extra);
        let o = play(scene, out, &args);
        assert!(o.status.success(), "{extra:?}: {}", text(&o));
        assert!(text(&o).contains("validation messages: 0"), "{extra:?}");
        let names = pass_names(out);
        if extra.contains(&"--no-blend") {
            assert!(!names.iter().any(|n| n == "pem_blend"), "{names:?}");
        }
        // The edge filter's two passes run only when asked for.
        let filtered = ["edge_copy", "edge_filter"].map(|p| names.iter().any(|n| n == p));
        let asked = extra.contains(&"--edge-filter");
        assert_eq!(filtered, [asked; 2], "{extra:?}: {names:?}");
    }
}

#[test]
fn main_job_compiles_what_is_missing_then_plays_every_mode() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = tiny_scene(dir.path());
    let out = dir.path().join("out");

    assert_first_run_compiles(&scene, &out);

    // The papers' multipass mode: the path passes between samples, so the
    // blend pass runs.
    let multi = play(&scene, &out, &["--compositing", "multipass"]);
    assert!(multi.status.success(), "{}", text(&multi));
    let names = pass_names(&out);
    for pass in ["pem", "pem_blend"] {
        assert!(names.iter().any(|n| n == pass), "{pass} missing: {names:?}");
    }

    // A second run compiles nothing.
    let again = play(&scene, &out, &["--no-capture"]);
    assert!(again.status.success(), "{}", text(&again));
    assert!(
        !text(&again).contains("tracing and inferring"),
        "{}",
        text(&again)
    );
    assert!(
        !text(&again).contains("ratio"),
        "re-encoded: {}",
        text(&again)
    );

    assert_path_is_scored(&scene, &out);
    assert_edited_scene_recompiles(&scene, &out);
    assert_bench_rows(&scene, &out);
    assert_every_mode_plays(&scene, &out);
}

#[test]
fn bad_pem_knobs_fail_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = tiny_scene(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).expect("mkdir");
    // Not a power of two / larger than the inferred maps: rejected before any work.
    for size in ["12", "32"] {
        let o = play(&scene, &out, &["--em-size", size]);
        assert!(!o.status.success());
        assert!(text(&o).contains("--em-size"), "{}", text(&o));
    }
    let o = play(&scene, &out, &["--spacing", "0"]);
    assert!(!o.status.success());
    // Maps the user named that are not there: a clear error, nothing made
    // there.
    let no_maps = dir.path().join("no-maps");
    let o = play(
        &scene,
        &out,
        &["--infer-dir", no_maps.to_str().expect("utf-8")],
    );
    assert!(!o.status.success());
    assert!(!text(&o).contains("panicked"), "{}", text(&o));
    assert!(
        text(&o).contains("no-maps") && text(&o).contains("maps missing"),
        "{}",
        text(&o)
    );
    assert!(!no_maps.exists(), "an input folder is never written");
}

/// A 2D viewpoint space (azimuth lines × elevation rings) compiles every
/// sample of every ring into a container of 2D parameter blocks (lines ×
/// rings) and plays the default path, which climbs through the rings,
/// validation-clean.
#[test]
fn a_2d_viewpoint_space_compiles_every_ring_and_plays() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = tiny_scene(dir.path());
    let text_of_scene = std::fs::read_to_string(&scene).expect("scene");
    let rings = text_of_scene.replacen(
        "samples = 3",
        "samples = 3\nrings = 2\nring_step_deg = 15.0",
        1,
    );
    assert_ne!(rings, text_of_scene, "the tiny scene sets samples");
    std::fs::write(&scene, rings).expect("write scene");
    let out = dir.path().join("out");
    let o = play(&scene, &out, &[]);
    let log = text(&o);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("validation messages: 0"), "{log}");
    for k in 0..6 {
        let map = out.join(format!("infer/sample_{k:04}/teapot.specular_local.exr"));
        assert!(map.is_file(), "{} missing", map.display());
    }
    assert!(!out.join("infer/sample_0006").exists());
    let container = codec::Container::open(&out.join("teapot.ptxc")).expect("container");
    for t in container.textures() {
        assert_eq!((t.grid.n0, t.grid.n1), (3, 2), "azimuth lines × rings");
        assert_eq!(t.log2b(), [3, 3], "8×8 parameter blocks");
    }
}

/// Lid and body as separate reflectors (the PEM paper's split, scene parts):
/// each compiles its own maps, the container holds both, and the frame
/// composites both, validation-clean.
#[test]
fn lid_and_body_as_separate_reflectors_compile_and_play() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = tiny_scene(dir.path());
    let source = std::fs::read_to_string(&scene).expect("scene");
    let start = source
        .find("[[objects]]\nname = \"teapot\"")
        .expect("the teapot object");
    let teapot = &source[start..];
    let part = |name: &str| {
        teapot
            .replacen("name = \"teapot\"", &format!("name = \"{name}\""), 1)
            .replacen(
                "segments = 6 }",
                &format!("segments = 6, part = \"{name}\" }}"),
                1,
            )
    };
    let split = format!("{}{}\n{}", &source[..start], part("body"), part("lid"));
    assert!(split.contains("part = \"lid\""), "{split}");
    std::fs::write(&scene, split).expect("write scene");
    let out = dir.path().join("out");
    let o = play(&scene, &out, &[]);
    let log = text(&o);
    assert!(o.status.success(), "{log}");
    assert!(log.contains("validation messages: 0"), "{log}");
    for object in ["body", "lid"] {
        let map = out.join(format!("infer/sample_0002/{object}.specular_local.exr"));
        assert!(map.is_file(), "{} missing", map.display());
    }
    let container = codec::Container::open(&out.join("teapot.ptxc")).expect("container");
    let parsed = inference::scene::Scene::load(scene.to_str().expect("utf-8")).expect("scene");
    let specs = engine::maps::map_specs(&parsed);
    let objects: std::collections::BTreeSet<&str> =
        specs.iter().map(|s| s.object.as_str()).collect();
    assert_eq!(objects, ["body", "lid"].into(), "maps of each reflector");
    assert_eq!(
        container.textures().len(),
        specs.len(),
        "every map in the container"
    );
    lid_at_half_the_resolution_plays(&scene, &out);
}

/// The lid with maps of half the body's resolution (its own map class):
/// only its maps compile again, deferred and multipass frames agree, and
/// the frame stays the one the lid's 16² maps draw up to what 8² maps lose
/// (a lid reading the body's maps, or its slots left empty, falls far
/// below).
fn lid_at_half_the_resolution_plays(scene: &Path, out: &Path) {
    let frame = |extra: &[&str]| {
        let mut args = vec!["--room", "analytic"];
        args.extend_from_slice(extra);
        let o = play(scene, out, &args);
        assert!(o.status.success(), "{extra:?}: {}", text(&o));
        assert!(text(&o).contains("validation messages: 0"), "{}", text(&o));
        let png = engine::capture::read_png(&out.join("frame_0001.png")).expect("frame");
        (text(&o), png.2)
    };
    let same_size = frame(&[]).1;
    let source = std::fs::read_to_string(scene).expect("scene");
    let lid = source.find("name = \"lid\"").expect("the lid");
    let at = lid
        + source[lid..]
            .find("resolution = 16")
            .expect("the lid's resolution");
    let half = format!("{}resolution = 8{}", &source[..at], &source[at + 15..]);
    std::fs::write(scene, half).expect("write scene");
    let (log, deferred) = frame(&[]);
    for (map, counts) in [
        ("body.specular_local", "3/0"),
        ("lid.specular_local", "0/3"),
    ] {
        assert!(log.contains(&format!("{map} {counts}")), "{map}: {log}");
    }
    let multipass = frame(&["--compositing", "multipass"]).1;
    // The PTM baseline plays from its own 2D map arrays per class.
    frame(&["--mode", "ptm"]);
    let container = codec::Container::open(&out.join("teapot.ptxc")).expect("container");
    let mut widths: Vec<u32> = container
        .textures()
        .iter()
        .map(|t| t.layout.width)
        .collect();
    widths.sort_unstable();
    // Each reflector's two EM layers, then both PTMs at the smallest PTM
    // edge (64², `engine::maps::PTM_MIN_EDGE`).
    assert_eq!(widths, [8, 8, 16, 16, 64, 64], "lid 8², body 16²");
    let paths = engine::compare::psnr(&deferred, &multipass);
    let halved = engine::compare::psnr(&same_size, &deferred);
    eprintln!(
        "lid at 8²: deferred against multipass {paths:.1} dB, against the 16² lid {halved:.1} dB"
    );
    assert!(paths >= 60.0, "deferred against multipass {paths:.1} dB");
    assert!(halved >= 45.0, "against the 16² lid {halved:.1} dB");
}
