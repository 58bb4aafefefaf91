//! `engine --light-path`: a light moving along the path, the reflector's
//! static EM relit for it every frame (SH maps through the codec), the room
//! lit by it; validation on.

mod common;

use common::*;
use std::path::Path;

/// Frame `i`'s pixels as linear-ish 0–1 floats (the PNG's 8-bit values).
fn frame(out: &Path, i: u32) -> Vec<f32> {
    let path = out.join(format!("frame_{i:04}.png"));
    let img = image::open(&path).expect("frame PNG").to_rgb8();
    img.as_raw().iter().map(|&v| f32::from(v) / 255.0).collect()
}

fn mean_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
}

fn play(out: &Path, extra: &[&str]) -> std::process::Output {
    let o = out.to_str().expect("utf-8");
    let mut args = vec!["--scene", "teapot", "--frames", "3", "--size", "96x72"];
    args.extend(["--light-path-size", "64x32", "--light-path-grid", "5x9"]);
    args.extend([
        "--light-path-spp",
        "1",
        "--no-video",
        "--validate",
        "--out",
        o,
    ]);
    args.extend(extra);
    run_engine(&args)
}

#[test]
fn a_moving_light_relights_the_reflector_and_the_room_every_frame() {
    let dir = tempfile::tempdir().expect("tempdir");
    for path in ["bulb", "sun"] {
        let out = dir.path().join(path);
        let o = play(&out, &["--light-path", path]);
        let log = output_text(&o);
        assert!(o.status.success(), "{log}");
        assert!(log.contains("validation messages: 0"), "{log}");
        for pass in ["relight", "panorama_cube", "room", "mirror"] {
            assert!(log.contains(&format!("\n{pass} ")), "{pass} pass: {log}");
        }
        let (first, last) = (frame(&out, 0), frame(&out, 2));
        let mean = first.iter().sum::<f32>() / first.len() as f32;
        assert!(mean > 0.01, "{path}: frame 0 is black ({mean})");
        let moved = mean_abs_diff(&first, &last);
        assert!(
            moved > 0.005,
            "{path}: the light moved, the frame did not ({moved})"
        );
        assert!(
            out.join("relight").is_dir(),
            "the grid is cached under --out"
        );
    }
    // The PEMs hold the scene's own lights: a moving light is refused there.
    let o = play(
        &dir.path().join("pem"),
        &["--light-path", "bulb", "--mode", "layered-pem"],
    );
    let log = output_text(&o);
    assert!(
        !o.status.success() && log.contains("--light-path with --mode layered-pem"),
        "{log}"
    );
}
