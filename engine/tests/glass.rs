//! Hybrid glass on the device: validation-clean frames; at IOR 1 the glass
//! vanishes (the frame equals the room without it); at IOR 1.5 it shows;
//! per-sample maps blend by azimuth and layered shells composite "over".

mod common;

use common::glass::*;
use common::*;
use engine::options::Mode;
use engine::renderer::{FrameMode, Renderer};
use inference::scene::Scene;
use std::path::Path;

const W: u32 = 160;
const H: u32 = 120;
/// Above this PSNR against the room, over the glass's pixels, the glass
/// has vanished; below it, it shows.
const VANISHED_DB: f64 = 35.0;

/// One frame of `scene` in `mode` from orbit azimuth 20°, 5° up.
fn frame(scene: &Scene, mode: FrameMode, tau: Option<f32>) -> Vec<[f32; 4]> {
    let device = validated_device();
    let mut renderer = Renderer::new(&device, scene, W, H).expect("renderer");
    if let (Some(g), Some(tau)) = (renderer.glass.as_mut(), tau) {
        g.tau = tau;
    }
    let eye = scene.orbit.eye(20.0, 5.0);
    renderer
        .frame(mode, eye, scene.orbit.view(eye))
        .expect("frame");
    let pixels = renderer.pixels().expect("pixels");
    if mode == FrameMode::Hybrid {
        let g = renderer.glass.as_ref().expect("glass player");
        assert!(g.last.triangles > 0 && g.last.rays > 0, "{:?}", g.last);
    }
    pixels
}

#[test]
fn ior_one_glass_vanishes_and_real_glass_shows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let air = [
        ("ior = 1.5", "ior = 1.0"),
        (
            "absorption = [0.6, 0.15, 0.3]",
            "absorption = [0.0, 0.0, 0.0]",
        ),
    ];
    let vanished = glass_scene(dir.path(), "air", &air);
    let glass = glass_scene(dir.path(), "glass", &[]);
    // The room alone: the teapot object gone.
    let mut room = glass_scene(dir.path(), "room", &[]);
    room.objects.retain(|o| o.glass.is_none());
    assert_eq!(Mode::default_for(&glass), Mode::Hybrid);
    assert_eq!(Mode::default_for(&room), Mode::LayeredPem);

    let room_px = frame(&room, FrameMode::StaticEm, None);
    let glass_px = frame(&glass, FrameMode::Hybrid, Some(10.0));
    // The glass's pixels: where the real glass changed the frame.
    let mask: Vec<bool> = glass_px
        .iter()
        .zip(&room_px)
        .map(|(g, r)| (0..3).any(|c| (g[c] - r[c]).abs() > 1e-3))
        .collect();
    let covered = mask.iter().filter(|m| **m).count();
    assert!(
        covered > (W * H / 20) as usize,
        "the glass covers {covered} pixels"
    );
    let shown = masked_psnr(&glass_px, &room_px, &mask);
    assert!(
        shown < 25.0,
        "IOR 1.5 glass should show: {shown:.1} dB against the room"
    );

    for tau in [3.0, 10.0] {
        let air_px = frame(&vanished, FrameMode::Hybrid, Some(tau));
        let psnr = masked_psnr(&air_px, &room_px, &mask);
        if psnr <= VANISHED_DB {
            let out = failure_dir();
            let _ = engine::capture::write_png(&out.join("glass_ior1.actual.png"), W, H, &air_px);
            let _ = engine::capture::write_png(&out.join("glass_ior1.room.png"), W, H, &room_px);
            let diff = engine::compare::diff_image(&room_px, &air_px, 8.0);
            let _ = engine::capture::write_png(&out.join("glass_ior1.diff.png"), W, H, &diff);
        }
        assert!(
            psnr > 35.0,
            "τ {tau}: IOR 1 glass vs the room, {psnr:.1} dB"
        );
    }
    // The same map read at infinity (the baseline's lookups) does not make
    // IOR 1 glass vanish: the shell's parallax is what the test measures.
    let at_infinity = frame(&vanished, FrameMode::StaticEm, None);
    let parallax = masked_psnr(&at_infinity, &room_px, &mask);
    assert!(
        parallax < VANISHED_DB,
        "lookups at infinity: {parallax:.1} dB"
    );
    // The baseline draws it too, through the same pass.
    let baseline = frame(&glass, FrameMode::StaticEm, None);
    let drawn = masked_psnr(&baseline, &room_px, &mask);
    assert!(
        drawn < VANISHED_DB,
        "the baseline draws the glass: {drawn:.1} dB"
    );
    assert_no_validation_messages();
}

#[test]
fn per_sample_shells_blend_by_the_eyes_azimuth() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = glass_scene(
        dir.path(),
        "glass",
        &[("resolution = 256", "resolution = 16")],
    );
    let (red, blue) = (
        constant_map(16, [1.0, 0.0, 0.0]),
        constant_map(16, [0.0, 0.0, 1.0]),
    );
    let device = validated_device();
    // Samples at 10° and 30°, the eye at 15°: a quarter of the way.
    let render = |maps: Vec<Vec<u8>>| {
        let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
        let shells = engine::glass::samples::SampleShells {
            azimuths: vec![10.0, 30.0],
            maps,
        };
        renderer.load_glass_samples(&shells).expect("samples");
        assert_eq!(renderer.glass.as_ref().map(|g| g.sample_count()), Some(2));
        let eye = scene.orbit.eye(15.0, 5.0);
        renderer
            .frame(FrameMode::Hybrid, eye, scene.orbit.view(eye))
            .expect("frame");
        renderer.pixels().expect("pixels")
    };
    let mixed = render(vec![red.clone(), blue.clone()]);
    let (all_red, all_blue) = (
        render(vec![red.clone(), red]),
        render(vec![blue.clone(), blue]),
    );
    let mut glass = 0;
    for ((m, r), b) in mixed.iter().zip(&all_red).zip(&all_blue) {
        if r[0] > 0.05 && b[2] > 0.05 {
            glass += 1;
        }
        for c in 0..3 {
            let expected = 0.75 * r[c] + 0.25 * b[c];
            assert!(
                (m[c] - expected).abs() <= 4e-3 * expected.max(1.0),
                "channel {c}: {} against 0.75 · {} + 0.25 · {}",
                m[c],
                r[c],
                b[c]
            );
        }
    }
    assert!(glass > (W * H / 20) as usize, "glass covers {glass} pixels");
    // The traced map at playback instead (the one-shell pipeline) is not
    // the blend: the test would see it.
    assert!(
        mixed
            .iter()
            .zip(&all_red)
            .any(|(m, r)| (m[2] - r[2]).abs() > 0.05)
    );
}

/// The glass scene with `size`² shell maps and two shells: a sphere
/// around the lens, then the room's box.
fn layered_scene(dir: &Path, size: u32) -> (Scene, inference::glass::ShellSet) {
    let scene = glass_scene(
        dir,
        "glass",
        &[("resolution = 256", &format!("resolution = {size}"))],
    );
    let g = scene
        .objects
        .iter()
        .find(|o| o.glass.is_some())
        .expect("glass");
    let origin = g.mesh.area_weighted_centroid();
    let mut set =
        inference::glass::room_shell(&scene, origin, inference::glass::room_box_shape(&scene));
    set.shells.insert(0, sphere_shell(0.8));
    (scene, set)
}

/// A sphere shell of `radius` around the lens holding no object.
fn sphere_shell(radius: f32) -> inference::glass::Shell {
    inference::glass::Shell {
        shape: inference::glass::ShellShape::Sphere { radius },
        objects: Vec::new(),
        distance: radius,
    }
}

#[test]
fn layered_shells_composite_each_inner_layer_over_the_outer() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (scene, two) = layered_scene(dir.path(), 16);
    let mut three = two.clone();
    three.shells.insert(0, sphere_shell(0.6));
    let device = validated_device();
    // One frame with constant layers (premultiplied; the last opaque).
    let render = |set: &inference::glass::ShellSet, layers: &[[f32; 4]]| {
        let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
        let maps: Vec<Vec<u8>> = layers.iter().map(|&l| constant_rgba(16, l)).collect();
        renderer.load_glass_layers(&maps, set).expect("layers");
        let n = renderer.glass.as_ref().map(|g| g.layer_count());
        assert_eq!(n, Some(layers.len() as u32));
        let eye = scene.orbit.eye(15.0, 5.0);
        renderer
            .frame(FrameMode::Hybrid, eye, scene.orbit.view(eye))
            .expect("frame");
        renderer.pixels().expect("pixels")
    };
    let (red, green, blue) = (
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
    );
    let clear = [0.0; 4];
    let (all_red, all_blue) = (render(&two, &[clear, red]), render(&two, &[clear, blue]));
    let all_green = render(&three, &[clear, clear, green]);
    // An opaque inner layer hides the outer one entirely; a quarter-covered
    // one lets three quarters through; of three, half of each in turn.
    let opaque = render(&two, &[red, blue]);
    let quarter = render(&two, &[[0.25, 0.0, 0.0, 0.25], blue]);
    let halves = render(&three, &[[0.5, 0.0, 0.0, 0.5], [0.0, 0.5, 0.0, 0.5], blue]);
    let mut glass = 0;
    for (i, ((r, g), b)) in all_red.iter().zip(&all_green).zip(&all_blue).enumerate() {
        if r[0] > 0.05 && b[2] > 0.05 {
            glass += 1;
        }
        for c in 0..3 {
            let expect = [
                ("opaque inner layer", opaque[i][c], r[c]),
                (
                    "quarter inner layer",
                    quarter[i][c],
                    0.25 * r[c] + 0.75 * b[c],
                ),
                (
                    "three half layers",
                    halves[i][c],
                    0.5 * r[c] + 0.25 * g[c] + 0.25 * b[c],
                ),
            ];
            for (what, got, expected) in expect {
                assert!(
                    (got - expected).abs() <= 4e-3 * expected.max(1.0),
                    "{what}, pixel {i}, channel {c}: {got} against {expected}"
                );
            }
        }
    }
    assert!(glass > (W * H / 20) as usize, "glass covers {glass} pixels");
}

/// A shell map of `size`² per face: `rgba` in the middle eighth of face 0
/// (+x) at level 0, transparent elsewhere, box-filtered down its levels.
fn spot_map(size: u32, rgba: [f32; 4]) -> Vec<u8> {
    let n = size as usize;
    let spot = n / 2 - n / 16..n / 2 + n / 16;
    let level0: Vec<[f32; 4]> = (0..6 * n * n)
        .map(|i| {
            let (face, x, y) = (i / (n * n), i % n, (i % (n * n)) / n);
            match face == 0 && spot.contains(&x) && spot.contains(&y) {
                true => rgba,
                false => [0.0; 4],
            }
        })
        .collect();
    inference::glass::shell_map::mip_chain(level0, size)
        .into_iter()
        .flatten()
        .flat_map(|t| t.map(half::f16::from_f32))
        .flat_map(half::f16::to_le_bytes)
        .collect()
}

#[test]
fn only_triangles_an_inner_layer_reaches_read_it_and_the_frame_stays() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (scene, set) = layered_scene(dir.path(), 64);
    let device = validated_device();
    let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
    let maps = vec![
        spot_map(64, [1.0, 0.0, 0.0, 1.0]),
        constant_map(64, [0.0, 0.0, 1.0]),
    ];
    renderer.load_glass_layers(&maps, &set).expect("layers");
    // Seen from −x, refraction lookups pass through the spot, most others
    // not.
    let eye = scene.orbit.eye(-90.0, 5.0);
    let draw = |renderer: &mut Renderer| {
        renderer
            .frame(FrameMode::Hybrid, eye, scene.orbit.view(eye))
            .expect("frame");
        let stats = renderer.glass.as_ref().expect("glass").last;
        (renderer.pixels().expect("pixels"), stats)
    };
    let (split, stats) = draw(&mut renderer);
    assert!(
        stats.layered_triangles > 0 && stats.layered_triangles < stats.triangles,
        "{stats:?}"
    );
    renderer
        .glass
        .as_mut()
        .expect("glass")
        .read_every_layer_everywhere();
    let (every, all) = draw(&mut renderer);
    assert_eq!(all.layered_triangles, all.triangles);
    let red = every.iter().filter(|p| p[0] > 0.05).count();
    assert!(red > 0, "the inner layer shows nowhere");
    let differ: Vec<f32> = (split.iter().zip(&every))
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max))
        .filter(|&d| d > 0.0)
        .collect();
    let largest = differ.iter().copied().fold(0.0, f32::max);
    assert!(
        differ.len() * 50 < red && largest < 0.05,
        "{} pixels differ (largest {largest}), {red} show the inner layer",
        differ.len()
    );
}

#[test]
fn per_sample_layers_blend_layer_by_layer_as_the_mixed_layers_draw() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (scene, set) = layered_scene(dir.path(), 16);
    let device = validated_device();
    // The eye at 15°, samples at 10° and 30°: a quarter of the way.
    let eye = scene.orbit.eye(15.0, 5.0);
    let draw = |renderer: &mut Renderer| {
        renderer
            .frame(FrameMode::Hybrid, eye, scene.orbit.view(eye))
            .expect("frame");
        renderer.pixels().expect("pixels")
    };
    let per_sample = |layers: [[[f32; 4]; 2]; 2]| {
        let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
        let samples = engine::glass::samples::LayerSamples {
            azimuths: vec![10.0, 30.0],
            layers: (0..2)
                .map(|k| layers.iter().map(|s| constant_rgba(16, s[k])).collect())
                .collect(),
        };
        renderer
            .load_glass_layer_samples(&samples, &set)
            .expect("per-sample layers");
        let g = renderer.glass.as_ref().expect("glass");
        assert_eq!((g.layer_count(), g.layer_sample_count()), (2, 2));
        draw(&mut renderer)
    };
    let traced = |layers: [[f32; 4]; 2]| {
        let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
        let maps: Vec<Vec<u8>> = layers.iter().map(|&l| constant_rgba(16, l)).collect();
        renderer.load_glass_layers(&maps, &set).expect("layers");
        draw(&mut renderer)
    };
    // Sample 0: a quarter-covering red inner layer over blue; sample 1: a
    // clear inner layer over green.
    let (s0, s1) = (
        [[0.25, 0.0, 0.0, 0.25], [0.0, 0.0, 1.0, 1.0]],
        [[0.0; 4], [0.0, 1.0, 0.0, 1.0]],
    );
    let blended = per_sample([s0, s1]);
    let mixed = traced([[0.1875, 0.0, 0.0, 0.1875], [0.0, 0.25, 0.75, 1.0]]);
    let first = traced(s0);
    let (mut glass, mut largest) = (0, 0.0f32);
    for ((b, m), f) in blended.iter().zip(&mixed).zip(&first) {
        for c in 0..3 {
            assert!(
                (b[c] - m[c]).abs() <= 4e-3 * m[c].max(1.0),
                "channel {c}: {} against the mixed layers' {}",
                b[c],
                m[c]
            );
            largest = largest.max((b[c] - f[c]).abs());
        }
        glass += usize::from(m[1] > 0.02 && m[2] > 0.05);
    }
    assert!(glass > (W * H / 20) as usize, "glass covers {glass} pixels");
    assert!(largest > 0.05, "the blend draws sample 0's layers alone");
    // Maps of another count than the shells are refused.
    let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
    let one = engine::glass::samples::LayerSamples {
        azimuths: vec![10.0, 30.0],
        layers: vec![vec![constant_rgba(16, [0.0; 4]); 2]],
    };
    assert!(renderer.load_glass_layer_samples(&one, &set).is_err());
    assert_no_validation_messages();
}
