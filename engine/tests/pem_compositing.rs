//! Deferred compositing draws what the papers' multipass draws: on a
//! sample (one map, no blending) and between samples (two maps blended),
//! the two frames agree — the G-buffer's explicit level of detail is the
//! one a forward `texture()` picks (LOD bias included), so maps inferred
//! through either path play in both. A diffuse card stands between the
//! eye and part of the teapot: the deferred frame draws the reflector
//! before the room, and the card must still hide it.

mod common;

use common::*;
use engine::compare::psnr;
use engine::pem::player::{Compositing, PemKind, PemSettings};
use engine::pem::samples::sample_blend;
use engine::pem::source::MapSource;
use engine::renderer::{FrameMode, Renderer};
use inference::scene::{Scene, ViewBlend};
use std::process::Command;

#[test]
fn deferred_and_multipass_frames_agree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut on_sample = Vec::new();
    // Without and with a LOD bias: the G-buffer adds it as `texture(…,
    // bias)` does, so both paths (and the probe renders) read the same levels.
    for (name, lod_bias) in [("plain", 0.0f32), ("biased", -2.0)] {
        let (scene, out) = compile(dir.path(), name, lod_bias);
        let report = std::fs::read_to_string(out.join("infer/sample_0000/report.json"))
            .expect("report.json");
        let report: serde_json::Value = serde_json::from_str(&report).expect("json");
        let a_vs_render = report["a_vs_render_psnr_db"].as_f64().expect("a_vs_render");
        assert!(
            a_vs_render > 100.0,
            "{name}: A x vs render {a_vs_render:.1} dB"
        );
        let device = validated_device();
        let orbit = scene.orbit.clone();
        let frame = |compositing, eye| draw(&device, &scene, &out, compositing, eye);
        for (what, eye, min_db) in [
            ("on a sample", orbit.sample_eye(1).expect("eye"), 100.0),
            (
                "between samples",
                orbit.eye(orbit.start_deg + 0.4 * orbit.step_deg, 0.0),
                85.0,
            ),
        ] {
            let deferred = frame(Compositing::Deferred, eye);
            let multipass = frame(Compositing::Multipass, eye);
            let db = psnr(&multipass, &deferred);
            eprintln!("{name}, {what}: deferred against multipass {db:.1} dB");
            assert!(db >= min_db, "{name}, {what}: {db:.1} dB");
        }
        on_sample.push(frame(
            Compositing::Deferred,
            orbit.sample_eye(1).expect("eye"),
        ));
        // Frames in flight: texgen and bands computed ahead for the view
        // the player announced draw the same frame as computed in line,
        // and a wrong announcement falls back to computing in line.
        let between = orbit.eye(orbit.start_deg + 0.4 * orbit.step_deg, 0.0);
        let inline = frame(Compositing::Deferred, between);
        for (what, announced) in [
            ("predicted", between),
            ("mispredicted", orbit.eye(7.0, 5.0)),
        ] {
            let mut r = Renderer::new(&device, &scene, 96, 72).expect("renderer");
            let settings = PemSettings {
                edge_filter: false,
                ..PemSettings::new(PemKind::Layered)
            };
            let source = MapSource::container(&scene, &out.join("teapot.ptxc")).expect("container");
            r.set_pem(&scene, settings, source).expect("set-up");
            let first = orbit.sample_eye(0).expect("eye");
            r.set_next_view(announced, orbit.view(announced));
            r.frame(FrameMode::Pem, first, orbit.view(first))
                .expect("frame");
            let stats = r
                .frame(FrameMode::Pem, between, orbit.view(between))
                .expect("frame");
            let pixels = r.pixels().expect("pixels");
            assert!(
                pixels == inline,
                "{name}: {what} next view drew another frame"
            );
            let expected = u32::from(what == "predicted");
            assert_eq!(stats.cpu.texgen_ahead, expected, "{name}: {what}");
        }
    }
    // The bias is applied: maps inferred and played with it draw another frame.
    let db = psnr(&on_sample[0], &on_sample[1]);
    assert!(db < 60.0, "the LOD bias changed nothing ({db:.1} dB)");
    assert_no_validation_messages();
}

/// The composite is compiled once per sample count (lavapipe pays for
/// every lookup a shader holds, taken or not): on a 2D grid whose upper
/// ring keeps every other line, views that blend 1, 2, 3 and 4 samples
/// each draw what multipass draws.
#[test]
fn every_composite_variant_draws_what_multipass_draws() {
    let dir = tempfile::tempdir().expect("tempdir");
    let rings = "rings = 2\nring_step_deg = 15.0\nring_line_every = 2\n";
    let (scene, out) = compile_with(dir.path(), "rings", -2.0, rings, true);
    let orbit = scene.orbit.clone();
    let grid = inference::scene::ViewGrid::from_orbit(&orbit);
    let device = validated_device();
    let frame = |compositing, eye| draw(&device, &scene, &out, compositing, eye);
    let (start, step) = (orbit.start_deg, orbit.step_deg);
    let mut counts = Vec::new();
    for (azimuth, elevation) in [
        (start + step, 0.0),
        (start + 0.5 * step, 0.0),
        (start + step, 7.5),
        (start + 0.5 * step, 7.5),
    ] {
        let eye = orbit.eye(azimuth, elevation);
        let samples = sample_blend(&grid, &orbit, eye, 1, true, ViewBlend::Bilinear)
            .samples
            .len();
        counts.push(samples);
        let db = psnr(
            &frame(Compositing::Multipass, eye),
            &frame(Compositing::Deferred, eye),
        );
        eprintln!(
            "{samples} samples at ({azimuth}, {elevation}): deferred against multipass {db:.1} dB"
        );
        assert!(db >= 85.0, "{samples} samples: {db:.1} dB");
    }
    assert_eq!(counts, [1, 2, 3, 4], "the views exercise every variant");
    assert_no_validation_messages();
}

/// The edge filter is the tracer's film filter (a Gaussian of σ = ½
/// pixel, as 3×3 taps of its variance) at exactly the pixels where the frame steps
/// between showing the reflector and not (four-neighbours), and nowhere
/// else: computed here on the CPU from the unfiltered frame, it matches
/// the device's to half-float precision — so the outline's tiles hold
/// every such pixel and the copy every pixel its taps read. With the card
/// in front of the teapot, the pixels it covers count as the room's and
/// its edge over the teapot (no outline of the teapot's) is left as
/// rasterized: every pixel is either the filter's or untouched.
#[test]
fn the_edge_filter_is_the_film_filter_along_the_outline() {
    let dir = tempfile::tempdir().expect("tempdir");
    let device = validated_device();
    for card in [false, true] {
        let name = if card { "card" } else { "open" };
        let (scene, out) = compile_with(dir.path(), name, 0.0, "", card);
        let orbit = scene.orbit.clone();
        let frame = |edge_filter: bool, eye: glam::Vec3| {
            let mut r = Renderer::new(&device, &scene, 96, 72).expect("renderer");
            let settings = PemSettings {
                edge_filter,
                ..PemSettings::new(PemKind::Layered)
            };
            let container = out.join("teapot.ptxc");
            let source = MapSource::container(&scene, &container).expect("container");
            r.set_pem(&scene, settings, source).expect("set-up");
            r.frame(FrameMode::Pem, eye, orbit.view(eye))
                .expect("frame");
            let mask = r.reflector_pixels().expect("mask");
            (r.pixels().expect("pixels"), mask)
        };
        for eye in [
            orbit.sample_eye(0).expect("eye"),
            orbit.eye(orbit.start_deg + 0.4 * orbit.step_deg, 5.0),
        ] {
            let (plain, mask) = frame(false, eye);
            let (filtered, filtered_mask) = frame(true, eye);
            assert_eq!(mask, filtered_mask, "the filter keeps the marks");
            let expected = film_filter_at_steps(&plain, &mask, 96, 72);
            let near = |a: &[f32; 4], b: &[f32; 4]| {
                (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-3 * a[c].abs().max(1.0) + 1e-4)
            };
            let (mut steps, mut left) = (0, 0);
            for (i, ((e, f), p)) in expected.iter().zip(&filtered).zip(&plain).enumerate() {
                let (x, y) = (i % 96, i / 96);
                let ok = near(e, f) || (card && f == p);
                assert!(
                    ok,
                    "{name} ({x}, {y}): expected {e:?}, drew {f:?}, unfiltered {p:?}"
                );
                steps += usize::from(e != p);
                left += usize::from(e != p && !near(e, f));
            }
            let covered = mask.iter().filter(|&&m| m).count();
            eprintln!("{name}: {covered} reflector pixels, {steps} steps, {left} left as drawn");
            assert!(
                covered > 100 && steps > 20,
                "{covered} covered, {steps} steps"
            );
            assert!(
                left < steps / 2,
                "{name}: {left} of {steps} steps left as drawn"
            );
        }
    }
    assert_no_validation_messages();
}

/// The 3×3 film filter (the Gaussian of σ = ½ pixel as three taps per
/// axis of the same variance, borders clamped) of `frame` at pixels whose
/// `mask` differs from a four-neighbour's; the rest as they are.
fn film_filter_at_steps(frame: &[[f32; 4]], mask: &[bool], w: i32, h: i32) -> Vec<[f32; 4]> {
    let at = |x: i32, y: i32| (y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize;
    // Each axis's taps have the film Gaussian's variance, σ² = ¼ (2w = ¼).
    let side = 0.125;
    let weight = |d: i32| if d == 0 { 1.0 - 2.0 * side } else { side };
    let mut out = frame.to_vec();
    for y in 0..h {
        for x in 0..w {
            let m = mask[at(x, y)];
            let step = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(dx, dy)| mask[at(x + dx, y + dy)] != m);
            if !step {
                continue;
            }
            let mut sum = [0.0f32; 3];
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let p = frame[at(x + dx, y + dy)];
                    for c in 0..3 {
                        sum[c] += weight(dx) * weight(dy) * p[c];
                    }
                }
            }
            let o = &mut out[at(x, y)];
            o[..3].copy_from_slice(&sum);
        }
    }
    out
}

/// One 96×72 layered-PEM frame from `eye`, played from `out`'s container.
fn draw(
    device: &engine::backend::Device,
    scene: &Scene,
    out: &std::path::Path,
    compositing: Compositing,
    eye: glam::Vec3,
) -> Vec<[f32; 4]> {
    let mut r = Renderer::new(device, scene, 96, 72).expect("renderer");
    let settings = PemSettings {
        compositing,
        // Bilinear, so a view between rings blends four samples.
        view_blend: ViewBlend::Bilinear,
        // Multipass has none: the compositing paths are what is compared.
        edge_filter: false,
        ..PemSettings::new(PemKind::Layered)
    };
    let source = MapSource::container(scene, &out.join("teapot.ptxc")).expect("container");
    r.set_pem(scene, settings, source).expect("set-up");
    r.frame(FrameMode::Pem, eye, scene.orbit.view(eye))
        .expect("frame");
    r.pixels().expect("pixels")
}

/// A diffuse card (both windings) in front of the teapot's right half as
/// the orbit's first samples see it: an occluder the room pass draws.
const CARD_OBJ: &str = "v 0.05 0.15 0.8\nv 0.45 0.15 0.8\nv 0.45 0.45 0.8\nv 0.05 0.45 0.8\n\
                        f 1 2 3\nf 1 3 4\nf 3 2 1\nf 4 3 1\n";
const CARD: &str = "
[[objects]]
name = \"card\"
mesh = { obj = \"card.obj\" }
material = \"floor\"
";

/// The tiny scene with `lod_bias` and the card, compiled into
/// `dir/<name>` at 96×72.
fn compile(dir: &std::path::Path, name: &str, lod_bias: f32) -> (Scene, std::path::PathBuf) {
    compile_with(dir, name, lod_bias, "", true)
}

/// [`compile`], `orbit` added after the orbit's `samples` line, with or
/// without the card.
fn compile_with(
    dir: &std::path::Path,
    name: &str,
    lod_bias: f32,
    orbit: &str,
    card: bool,
) -> (Scene, std::path::PathBuf) {
    let scene_path = tiny_scene(dir);
    std::fs::write(dir.join("card.obj"), CARD_OBJ).expect("write card");
    let text = std::fs::read_to_string(&scene_path).expect("scene") + if card { CARD } else { "" };
    let with_orbit = text.replacen("samples = 3\n", &format!("samples = 3\n{orbit}"), 1);
    assert!(
        orbit.is_empty() || with_orbit != text,
        "the tiny scene sets samples"
    );
    let text = with_orbit;
    // The tiny scene inherits the shipped teapot's bias: replace its line.
    let text: String = text
        .lines()
        .map(|l| {
            if l.starts_with("lod_bias =") {
                format!("lod_bias = {lod_bias:?}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    assert!(
        text.contains(&format!("lod_bias = {lod_bias:?}\n")),
        "teapot.toml lacks lod_bias"
    );
    let scene_path = dir.join(format!("{name}.toml"));
    std::fs::write(&scene_path, text).expect("write scene");
    let out = dir.join(name);
    let o = Command::new(env!("CARGO_BIN_EXE_engine"))
        .args([
            "--scene",
            scene_path.to_str().expect("utf-8"),
            "--size",
            "96x72",
        ])
        .args([
            "--frames",
            "1",
            "--no-capture",
            "--out",
            out.to_str().expect("utf-8"),
        ])
        .output()
        .expect("run engine");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let scene = Scene::load(scene_path.to_str().expect("utf-8")).expect("scene");
    (scene, out)
}
