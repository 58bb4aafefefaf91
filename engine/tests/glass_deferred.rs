//! Deferred glass on the device: per-sample shell maps composited from a
//! G-buffer draw the forward frame, and a lens off the frame draws no
//! glass pass.

mod common;

use common::glass::*;
use common::*;
use engine::renderer::{FrameMode, Renderer};

const W: u32 = 160;
const H: u32 = 120;

/// A shell map of `size`² per face whose colour says where a lookup
/// landed: red the MIP level, green and blue the texel's place on its face
/// (`swap` exchanges them, for a second sample).
fn level_coded_map(size: u32, swap: bool) -> Vec<u8> {
    let levels = size.ilog2();
    let mut bytes = Vec::new();
    for level in 0..=levels {
        let n = size >> level;
        for _face in 0..6 {
            for y in 0..n {
                for x in 0..n {
                    let (u, v) = ((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
                    let (g, b) = if swap { (v, u) } else { (u, v) };
                    let texel = [level as f32 / levels as f32, g, b, 1.0];
                    bytes.extend(
                        texel
                            .map(half::f16::from_f32)
                            .iter()
                            .flat_map(|h| h.to_le_bytes()),
                    );
                }
            }
        }
    }
    bytes
}

/// A diffuse card (both windings) between the orbit's first views and the
/// lens's right half: an occluder the room pass draws.
const CARD_OBJ: &str = "v 0.05 0.15 0.8\nv 0.45 0.15 0.8\nv 0.45 0.45 0.8\nv 0.05 0.45 0.8\n\
                        f 1 2 3\nf 1 3 4\nf 3 2 1\nf 4 3 1\n";

/// The small glass scene, with or without the card.
fn scene_with(dir: &std::path::Path, card: bool) -> inference::scene::Scene {
    let name = if card { "card" } else { "glass" };
    let scene = glass_scene(dir, name, &[("resolution = 256", "resolution = 32")]);
    if !card {
        return scene;
    }
    std::fs::write(dir.join("card.obj"), CARD_OBJ).expect("write card");
    let path = dir.join("card.toml");
    let text = std::fs::read_to_string(&path).expect("scene")
        + "\n[[objects]]\nname = \"card\"\nmesh = { obj = \"card.obj\" }\nmaterial = \"floor\"\n";
    std::fs::write(&path, text).expect("write scene");
    inference::scene::Scene::load(path.to_str().expect("utf-8 path")).expect("card scene")
}

#[test]
fn deferred_glass_draws_the_forward_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let open = deferred_against_forward(&scene_with(dir.path(), false));
    let card = deferred_against_forward(&scene_with(dir.path(), true));
    // The card hides part of the lens (else the second case tests nothing).
    let hidden = (open.iter().zip(&card))
        .filter(|(o, c)| **o && !**c)
        .count();
    assert!(hidden > 100, "the card hides {hidden} lens pixels");
}

/// The deferred frame (its G-buffer before the room) against the forward
/// one (after it): the room the same bit for bit, the lens within 50 dB.
/// With the card, the room pass unmarks the lens's pixels it covers, so
/// the composite leaves the card as drawn. Returns the lens's pixels.
fn deferred_against_forward(scene: &inference::scene::Scene) -> Vec<bool> {
    let scene = scene.clone();
    let device = validated_device();
    let render = |maps: Vec<Vec<u8>>, deferred: bool| {
        let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
        let shells = engine::glass::samples::SampleShells {
            azimuths: vec![10.0, 30.0],
            maps,
        };
        // Read when the maps are set.
        renderer.glass.as_mut().expect("glass player").deferred = deferred;
        renderer.load_glass_samples(&shells).expect("samples");
        let eye = scene.orbit.eye(15.0, 5.0);
        let stats = renderer
            .frame(FrameMode::Hybrid, eye, scene.orbit.view(eye))
            .expect("frame");
        // The path asked for is the path drawn.
        let gbuffer = stats.passes.iter().any(|p| p.name == "glass_gbuffer");
        assert_eq!(gbuffer, deferred, "{:?}", stats.passes);
        renderer.pixels().expect("pixels")
    };
    let coded = || vec![level_coded_map(32, false), level_coded_map(32, true)];
    let forward = render(coded(), false);
    let deferred = render(coded(), true);
    // The lens's pixels: wherever black maps change the frame (the rest,
    // the room, must then match bit for bit).
    let black = render(vec![constant_map(32, [0.0; 3]); 2], true);
    let mask: Vec<bool> = (forward.iter().zip(&black)).map(|(f, b)| f != b).collect();
    let lens = mask.iter().filter(|m| **m).count();
    assert!(
        lens > (W * H / 20) as usize,
        "the lens covers {lens} pixels"
    );
    // Same lookups, same levels of detail, same weights: a level off or
    // a lookup a texel off would show in red, green or blue.
    let db = masked_psnr(&forward, &deferred, &mask);
    assert!(
        db > 50.0,
        "deferred against forward over the lens: {db:.2} dB"
    );
    let room: Vec<bool> = mask.iter().map(|m| !m).collect();
    assert!(masked_psnr(&forward, &deferred, &room).is_infinite());
    assert_no_validation_messages();
    mask
}

#[test]
fn a_lens_beside_the_frame_draws_no_glass_passes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = glass_scene(
        dir.path(),
        "glass",
        &[("resolution = 256", "resolution = 16")],
    );
    let device = validated_device();
    let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
    let shells = engine::glass::samples::SampleShells {
        azimuths: vec![10.0, 30.0],
        maps: vec![constant_map(16, [1.0, 0.0, 0.0]); 2],
    };
    renderer.load_glass_samples(&shells).expect("samples");
    let (lo, hi) = renderer.glass.as_ref().expect("glass player").bounds();
    let eye = scene.orbit.eye(15.0, 5.0);
    // Looking 60° to the side of the lens: in front of the eye, off the
    // frame, so its render area is empty (an invalid render area).
    let towards = ((lo + hi) * 0.5 - eye).normalize();
    let aside = glam::Quat::from_rotation_y(60f32.to_radians()) * towards;
    let view = glam::camera::rh::view::look_to_mat4(eye, aside, glam::Vec3::Y);
    let stats = renderer.frame(FrameMode::Hybrid, eye, view).expect("frame");
    let names: Vec<&str> = stats.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["room", "readback"]);
    assert_no_validation_messages();
}
