//! Hostile but realistic input: the engine never replaces a file it did
//! not write, never plays stale or damaged compiled inputs as good, keeps
//! to its output folder, and stops with one clear line where it cannot go
//! on. Each check failed before the rules of the README's *Reliability*
//! section were enforced.

mod common;

use common::{output_text as log, tiny_scene};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn engine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

/// A failed run: non-zero exit, no panic, an `error:` line with every needle.
fn assert_refused(o: &Output, needles: &[&str]) {
    let text = log(o);
    assert!(!o.status.success(), "expected a failure:\n{text}");
    assert!(!text.contains("panicked"), "{text}");
    let line = text
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no error line:\n{text}"));
    for n in needles {
        assert!(line.contains(n), "error line lacks {n:?}: {line}");
    }
}

/// Plays the tiny scene into `out` (layered PEMs unless `extra` says).
fn play(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "--scene",
        s(scene),
        "--size",
        "64x48",
        "--frames",
        "2",
        "--warmup",
        "0",
        "--out",
        s(out),
        "--no-capture",
    ];
    args.extend_from_slice(extra);
    engine(&args)
}

/// What a file holds now, to prove it untouched.
fn snapshot(p: &Path) -> Vec<u8> {
    std::fs::read(p).expect("read")
}

fn compiled(dir: &Path) -> (PathBuf, PathBuf) {
    let scene = tiny_scene(dir);
    let out = dir.join("out");
    let o = play(&scene, &out, &[]);
    assert!(o.status.success(), "{}", log(&o));
    (scene, out)
}

#[test]
fn foreign_files_and_folders_are_never_overwritten() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (scene, out) = compiled(dir.path());
    let container = out.join("teapot.ptxc");

    // A text file, and a copy of a real container without its record, as
    // --container: refused by name, the scene named as the user named it.
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "my notes").expect("write");
    let o = play(&scene, &out, &["--container", s(&notes)]);
    assert_refused(&o, &["notes.txt", "no key record", s(&scene)]);
    assert_eq!(snapshot(&notes), b"my notes");
    let copy = dir.path().join("copy.ptxc");
    std::fs::copy(&container, &copy).expect("copy");
    let before = snapshot(&copy);
    assert_refused(
        &play(&scene, &out, &["--container", s(&copy)]),
        &["copy.ptxc", "no key record"],
    );
    assert_eq!(snapshot(&copy), before);
    // `engine encode --out` onto a file it did not write: refused.
    let o = engine(&[
        "encode",
        "--scene",
        s(&scene),
        "--infer-dir",
        s(&out.join("infer")),
        "--out",
        s(&notes),
    ]);
    assert_refused(&o, &["notes.txt", "not overwritten"]);
    assert_eq!(snapshot(&notes), b"my notes");
    // A foreign file where the engine's own container would go.
    inference::key::forget(&container);
    std::fs::write(&container, "someone's file").expect("write");
    assert_refused(
        &play(&scene, &out, &[]),
        &["teapot.ptxc", "not overwritten"],
    );
    assert_eq!(snapshot(&container), b"someone's file");
    // A non-empty folder the engine did not make, as --out.
    let theirs = dir.path().join("theirs");
    std::fs::create_dir(&theirs).expect("mkdir");
    std::fs::write(theirs.join("thesis.tex"), "x").expect("write");
    assert_refused(
        &play(&scene, &theirs, &["--mode", "static-em"]),
        &["theirs", "did not make"],
    );
    let names: Vec<_> = std::fs::read_dir(&theirs).expect("ls").collect();
    assert_eq!(names.len(), 1, "nothing written into a foreign folder");
    // An empty --infer-dir: an input, reported, never written into.
    let empty = dir.path().join("empty-maps");
    std::fs::create_dir(&empty).expect("mkdir");
    assert_refused(
        &play(&scene, &out, &["--infer-dir", s(&empty)]),
        &["empty-maps", "maps missing"],
    );
    assert_eq!(std::fs::read_dir(&empty).expect("ls").count(), 0);
}

#[test]
fn damaged_or_out_of_range_compiled_files_are_rebuilt_not_trusted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (scene, out) = compiled(dir.path());
    let infer = out.join("infer");
    let trace = out.join("trace");
    let infer_all = |extra: &[&str]| {
        let mut args = vec![
            "infer",
            "--scene",
            s(&scene),
            "--all",
            "--size",
            "64x48",
            "--out",
            s(&infer),
            "--trace-dir",
            s(&trace),
        ];
        args.extend_from_slice(extra);
        engine(&args)
    };
    // A truncated map is inferred again, not called up to date.
    let map = infer.join("sample_0001/teapot.specular_local.exr");
    let bytes = snapshot(&map);
    std::fs::write(&map, &bytes[..bytes.len() / 2]).expect("truncate");
    let o = infer_all(&[]);
    assert!(o.status.success(), "{}", log(&o));
    assert!(log(&o).contains("its record says"), "{}", log(&o));
    assert!(
        log(&o).contains("sample   1 teapot.specular_local"),
        "{}",
        log(&o)
    );
    assert_eq!(snapshot(&map).len(), bytes.len());
    // A truncated traced image is traced again when a map needs it.
    let traced = out.join("trace/sample_0002.exr");
    let t = snapshot(&traced);
    std::fs::write(&traced, &t[..t.len() / 3]).expect("truncate");
    inference::key::forget(&infer.join("sample_0002/teapot.ptm.exr"));
    let o = infer_all(&[]);
    assert!(o.status.success(), "{}", log(&o));
    assert!(log(&o).contains("tracing it again"), "{}", log(&o));
    // A map holding values playback cannot (beyond f16) is never played
    // dark: from EXR it is an error naming it, through the container it is
    // inferred again.
    let huge = infer.join("sample_0000/teapot.specular_distant.exr");
    let layout = inference::solve::layout::TextureLayout::full_chain(
        inference::solve::layout::TextureShape::Cube { size: 16 },
    );
    let record = inference::key::read_record(&huge).expect("record");
    inference::infer::maps::write_map(&huge, &layout, &vec![vec![1e30; layout.len()]; 3])
        .expect("write");
    inference::key::write_record(&huge, &record.key).expect("record");
    assert_refused(
        &play(&scene, &out, &["--maps", "exr"]),
        &["teapot.specular_distant.exr", "f16"],
    );
    inference::key::forget(&out.join("teapot.ptxc"));
    let o = play(&scene, &out, &[]);
    assert!(o.status.success(), "{}", log(&o));
    assert!(log(&o).contains("inferring it again"), "{}", log(&o));
}

#[test]
fn small_maps_are_encoded_at_a_size_that_holds_their_quality() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (scene, out) = compiled(dir.path());
    let scene = inference::scene::Scene::load(s(&scene)).expect("scene");
    let input = engine::compile::encode::load_input(
        &scene,
        engine::maps::MapSet::Scene,
        &out.join("infer"),
        engine::compile::encode::MapsFor::Encode,
    )
    .expect("maps");
    let c = codec::Container::open(&out.join("teapot.ptxc")).expect("container");
    let mut cache = codec::DecodeCache::default();
    for t in &input.textures {
        let mut acc = codec::quality::PsnrAccum::default();
        let mut decoded = vec![0.0f32; t.layout.texels() * 4];
        for k in 0..t.grid.n0 {
            cache
                .decode_leaf_all(&c, t.id.object, t.id.layer, [k, 0], &mut decoded)
                .expect("decode");
            acc.add(
                t.sample(k as usize),
                t.layout.channels as usize,
                &decoded,
                4,
            );
        }
        // The default ratio gave 11-14 dB here: a teapot played black.
        assert!(
            acc.psnr_db() >= engine::compile::encode::MIN_TEXTURE_PSNR_DB,
            "{}",
            acc.psnr_db()
        );
    }
}

#[test]
fn concurrent_runs_into_one_folder_all_succeed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let runs: Vec<_> = (0..3)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_engine"))
                .args([
                    "--mode",
                    "static-em",
                    "--size",
                    "48x32",
                    "--frames",
                    "3",
                    "--warmup",
                    "0",
                    "--out",
                    s(&out),
                ])
                .output()
        })
        .collect();
    for r in runs {
        let o = r.expect("run");
        assert!(o.status.success(), "{}", log(&o));
    }
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .expect("ls")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn a_copied_binary_finds_its_scenes_without_the_build_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bin = dir.path().join("engine");
    std::fs::copy(env!("CARGO_BIN_EXE_engine"), &bin).expect("copy binary");
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).expect("mkdir");
    let o = Command::new(&bin)
        .current_dir(&elsewhere)
        // The old way to find scenes, pointed at nothing.
        .env("ENGINE_ASSETS", &elsewhere)
        .args([
            "--scene",
            "teapot",
            "--mode",
            "static-em",
            "--size",
            "32x24",
            "--frames",
            "1",
            "--warmup",
            "0",
        ])
        .output()
        .expect("run the copy");
    assert!(o.status.success(), "{}", log(&o));
    assert!(elsewhere.join("out/teapot/frame_0000.png").is_file());
}

#[test]
fn limits_are_checked_before_any_work_with_the_field_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = tiny_scene(dir.path());
    let text = std::fs::read_to_string(&scene).expect("scene");
    let variant = |name: &str, from: &str, to: &str| {
        assert!(text.contains(from), "tiny scene lacks {from}");
        let p = dir.path().join(name);
        std::fs::write(&p, text.replacen(from, to, 1)).expect("write");
        p
    };
    let many = variant("many.toml", "samples = 3", "samples = 100000");
    assert_refused(
        &play(&many, &dir.path().join("o1"), &[]),
        &["orbit.samples", "100000", "4096"],
    );
    let big = variant("big.toml", "resolution = 16", "resolution = 4096");
    assert_refused(
        &play(&big, &dir.path().join("o2"), &[]),
        &["objects[0].em.resolution", "2048"],
    );
    let o = engine(&[
        "infer",
        "--scene",
        s(&scene),
        "--sample",
        "0",
        "--em-size",
        "65536",
        "--out",
        s(&dir.path().join("o3")),
    ]);
    assert_refused(&o, &["--em-size 65536", "power of two from 4 to 2048"]);
    for (file, name) in [
        ("up.toml", "../../x"),
        ("abs.toml", "/abs/x"),
        ("empty.toml", ""),
    ] {
        let p = variant(file, "name = \"teapot\"", &format!("name = {name:?}"));
        assert_refused(
            &play(&p, &dir.path().join("o4"), &[]),
            &[file, "name", "output folder"],
        );
    }
    let o = play(&scene, &dir.path().join("o5"), &["--frames", "0"]);
    assert!(
        !o.status.success() && log(&o).contains("--frames"),
        "{}",
        log(&o)
    );
    assert!(!dir.path().join("x").exists() && !dir.path().join("o4").exists());
}
