//! A reflector's inside: where the eye looks between the teapot's lid and
//! body, the tracer's primary rays hit the inside (back faces) and see it
//! dark; the rasterizer culls back faces, so without the caps over the
//! openings (`inference::caps`, `passes::interior`) those pixels showed
//! the room through the teapot (~0.3 linear against ~0). The default
//! (deferred) frame, the static EM frame and the REM frame draw them dark,
//! also where a part of the teapot lies behind the opening (the body seen
//! into the spout's mouth, whose stencil mark the cap must clear).
//! An open surface (a mirror pane) is not a solid with openings: it keeps
//! its reflection.

mod common;

use common::*;
use engine::pem::player::{PemKind, PemSettings};
use engine::pem::source::MapSource;
use engine::rem::sources::{RemSettings, reflector, trace};
use engine::renderer::{FrameMode, Renderer};
use inference::scene::Scene;
use inference::trace::SceneBvh;
use inference::trace::camera::CameraRays;

const SIZE: (u32, u32) = (640, 480);

/// The pixels whose centre ray first meets the teapot from inside (or,
/// with `front`, from outside).
fn pixels_seeing_the_inside(scene: &Scene, eye: glam::Vec3) -> Vec<usize> {
    pixels_on_the_reflector(scene, eye, false)
}

fn pixels_on_the_reflector(scene: &Scene, eye: glam::Vec3, front: bool) -> Vec<usize> {
    let bvh = SceneBvh::build(scene);
    let cam = CameraRays::new(scene, eye, SIZE.0, SIZE.1);
    let teapot = scene.objects.iter().position(|o| o.name == "teapot");
    let mut inside = Vec::new();
    for py in 0..SIZE.1 {
        for px in 0..SIZE.0 {
            let (o, d) = cam.ray(px as f32 + 0.5, py as f32 + 0.5);
            let Some(h) = bvh.closest(o, d, 0.0, f32::INFINITY, None) else {
                continue;
            };
            if Some(h.prim.object as usize) != teapot {
                continue;
            }
            let mesh = &scene.objects[h.prim.object as usize].mesh;
            let [a, b, c] = mesh.triangle(h.prim.triangle as usize);
            if ((b - a).cross(c - a).dot(d) > 0.0) != front {
                inside.push((py * SIZE.0 + px) as usize);
            }
        }
    }
    inside
}

#[test]
fn the_lid_gap_and_the_spout_show_the_dark_inside_not_the_room() {
    let scene = Scene::load("teapot").expect("teapot scene");
    let container = engine::compile::shipped::root().join("teapot/teapot.ptxc");
    let device = validated_device();
    // REM from small, quickly traced source maps (the inside does not
    // depend on them).
    let rem_settings = RemSettings {
        size: 32,
        level: 0,
        spp: 4,
        lobe_samples: 4,
    };
    let object = reflector(&scene).expect("reflector");
    let rem_maps = trace(&scene, object, rem_settings).expect("REM source maps");
    // On the orbit at 12°: 96 pixels of the lid's gap (the README's view).
    // At 79.4°, 7.9° up (the main job's frame 119): the spout's mouth, with
    // the body behind it: the deferred frame shaded the cap there with the
    // body's mark (brown; 324 of its 639 pixels dark).
    for (azimuth, elevation) in [(12.0, 0.0), (79.4, 7.92)] {
        let eye = scene.orbit.eye(azimuth, elevation);
        let inside = pixels_seeing_the_inside(&scene, eye);
        assert!(inside.len() >= 50, "{} pixels see the inside", inside.len());
        for mode in [FrameMode::Pem, FrameMode::StaticEm, FrameMode::Rem] {
            let mut r = Renderer::new(&device, &scene, SIZE.0, SIZE.1).expect("renderer");
            if mode == FrameMode::Pem {
                let source = MapSource::container(&scene, &container).expect("shipped container");
                let settings = PemSettings::new(PemKind::Layered);
                r.set_pem(&scene, settings, source).expect("set-up");
            }
            if mode == FrameMode::Rem {
                r.set_rem(&scene, &rem_maps, true).expect("REM set-up");
            }
            r.frame(mode, eye, scene.orbit.view(eye)).expect("frame");
            let pixels = r.pixels().expect("pixels");
            assert_mostly_dark(&pixels, &inside, mode, azimuth);
            // Inferred maps hold a few texels below zero; the frame shows
            // no negative light (shaders/common.glsl, clamp_light).
            let negative = pixels.iter().filter(|p| p[..3].iter().any(|&c| c < 0.0));
            assert_eq!(
                negative.count(),
                0,
                "{mode:?} at {azimuth}°: negative light"
            );
        }
    }
    assert_no_validation_messages();
}

/// Nearly all of `inside` dark: a pixel's centre may land on a front face
/// in one and not the other (rounding at the rim).
fn assert_mostly_dark(pixels: &[[f32; 4]], inside: &[usize], mode: FrameMode, azimuth: f32) {
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let dark = inside
        .iter()
        .filter(|&&i| luminance(&pixels[i]) < 0.02)
        .count();
    assert!(
        dark * 10 >= inside.len() * 9,
        "{mode:?} at {azimuth}°: {dark} of {} inside pixels dark",
        inside.len()
    );
}

#[test]
fn a_mirror_pane_keeps_its_reflection() {
    // The teapot replaced by a square mirror pane facing the eye's side
    // (0.96 m wide at the object's scale): its outline is a boundary loop,
    // but a cap over it would be the pane itself, drawn black.
    let dir = tempfile::tempdir().expect("tempdir");
    let pane = inference::scene::Mesh {
        positions: [(-3.0, 0.0), (3.0, 0.0), (3.0, 6.0), (-3.0, 6.0)]
            .map(|(x, y)| glam::Vec3::new(x, y, 0.0))
            .to_vec(),
        normals: vec![glam::Vec3::Z; 4],
        uvs: vec![glam::Vec2::ZERO; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
    };
    inference::scene::obj::write_obj(&dir.path().join("pane.obj"), &pane, "pane")
        .expect("write pane");
    let tiny = std::fs::read_to_string(tiny_scene(dir.path())).expect("tiny scene");
    let text = tiny.replacen(
        "mesh = { generator = \"newell_teapot\", segments = 6 }",
        "mesh = { obj = \"pane.obj\" }",
        1,
    );
    assert!(text != tiny, "the tiny scene's teapot line moved");
    let path = dir.path().join("pane.toml");
    std::fs::write(&path, text).expect("write scene");
    let scene = Scene::load(path.to_str().expect("utf-8")).expect("pane scene");
    let eye = scene.orbit.eye(12.0, 0.0);
    let on_pane = pixels_on_the_reflector(&scene, eye, true);
    assert!(on_pane.len() >= 10_000, "{} pane pixels", on_pane.len());
    let device = validated_device();
    let mut r = Renderer::new(&device, &scene, SIZE.0, SIZE.1).expect("renderer");
    r.frame(FrameMode::StaticEm, eye, scene.orbit.view(eye))
        .expect("frame");
    let pixels = r.pixels().expect("pixels");
    let black = on_pane
        .iter()
        .filter(|&&i| pixels[i][..3].iter().all(|&c| c < 1e-4))
        .count();
    assert!(
        black * 100 <= on_pane.len(),
        "{black} of {} pane pixels black",
        on_pane.len()
    );
    assert_no_validation_messages();
}
