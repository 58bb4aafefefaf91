//! Shared by the integration tests: a validated lavapipe device per test and
//! golden-image comparison that writes the diff on failure.

#![allow(dead_code)] // each test binary uses a different subset

use engine::backend::{Device, DeviceOptions, create_device, validation};
use engine::capture;
use engine::compare;
use std::path::{Path, PathBuf};

/// A device with the Khronos validation layer on.
pub fn validated_device() -> Device {
    create_device(&DeviceOptions {
        device_name: None,
        validate: true,
    })
    .expect("lavapipe with the validation layer (ci/setup.sh installs both)")
}

/// Fails the test if any validation message was printed so far.
pub fn assert_no_validation_messages() {
    assert_eq!(
        validation::message_count(),
        0,
        "validation messages (see stderr)"
    );
}

pub fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

pub fn failure_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/golden-failures");
    std::fs::create_dir_all(&dir).expect("target/ is writable");
    dir
}

/// Compares `pixels` with the committed golden PNG `name` at `min_psnr_db`.
/// `UPDATE_GOLDEN=1` rewrites the golden instead. On failure writes the
/// frame and a ×8 diff image into target/golden-failures/.
pub fn assert_matches_golden(
    name: &str,
    width: u32,
    height: u32,
    pixels: &[[f32; 4]],
    min_psnr_db: f64,
) {
    let golden = golden_dir().join(format!("{name}.png"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        capture::write_png(&golden, width, height, pixels).expect("write golden");
        return;
    }
    let (gw, gh, reference) = capture::read_png(&golden)
        .unwrap_or_else(|e| panic!("{e} (run with UPDATE_GOLDEN=1 to create it)"));
    assert_eq!((gw, gh), (width, height), "golden {name} size");
    // Compare what the PNG can hold: the frame quantised the same way.
    let quantised: Vec<[f32; 4]> = pixels
        .iter()
        .map(|p| {
            let q = |c: f32| {
                capture::srgb_to_linear((capture::linear_to_srgb(c) * 255.0 + 0.5).floor() / 255.0)
            };
            [q(p[0]), q(p[1]), q(p[2]), 1.0]
        })
        .collect();
    let psnr = compare::psnr(&reference, &quantised);
    if psnr < min_psnr_db {
        let dir = failure_dir();
        let _ = capture::write_png(
            &dir.join(format!("{name}.actual.png")),
            width,
            height,
            pixels,
        );
        let diff = compare::diff_image(&reference, &quantised, 8.0);
        let _ = capture::write_png(&dir.join(format!("{name}.diff.png")), width, height, &diff);
        panic!(
            "{name}: PSNR {psnr:.2} dB against the golden image, need ≥ {min_psnr_db} dB; frame and diff in {}",
            dir.display()
        );
    }
}

/// The teapot scene with 3 samples, 16² maps, a coarse teapot and no views
/// above the plane.
pub fn tiny_scene(dir: &Path) -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes/teapot.toml");
    let text = std::fs::read_to_string(source).expect("teapot.toml");
    // Views above are traced per grid azimuth: compile_cli tests them alone.
    let mut text = inference::scene::shipped::without_views_above(&text);
    for (from, to) in [
        ("samples = 100", "samples = 3"),
        ("resolution = 256", "resolution = 16"),
        ("segments = 25 }", "segments = 6 }"),
    ] {
        assert!(text.contains(from), "teapot.toml lacks {from:?}");
        text = text.replacen(from, to, 1);
    }
    let path = dir.join("tiny.toml");
    std::fs::write(&path, text).expect("write scene");
    path
}

/// Runs the `engine` binary with `args`.
pub fn run_engine(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

/// A run's exit status, stdout and stderr, for assertion messages and log
/// checks (the status names the signal when the engine died of one).
pub fn output_text(o: &std::process::Output) -> String {
    format!(
        "{}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The free views a compile traced under `out/trace` (`view_*.exr`), sorted.
pub fn traced_views(out: &Path) -> Vec<String> {
    let mut views: Vec<String> = std::fs::read_dir(out.join("trace"))
        .expect("trace folder")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("view_") && n.ends_with(".exr"))
        .collect();
    views.sort();
    views
}
pub mod glass;
pub mod glass_cli;
