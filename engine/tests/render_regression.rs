//! Renders small frames of the teapot scene on lavapipe with validation on
//! and compares them with golden images committed in tests/golden/.
//!
//! Tolerance: 45 dB PSNR on the 8-bit sRGB frame. Rendering is
//! deterministic on one device, so this only absorbs driver-version noise
//! (a Mesa update); a one-texel shift of the teapot drops far below it.

mod common;

use common::*;
use engine::renderer::{FrameMode, Renderer};
use inference::scene::Scene;

const W: u32 = 160;
const H: u32 = 120;
const MIN_PSNR_DB: f64 = 45.0;

fn render(mode: FrameMode, sample: u32) -> Vec<[f32; 4]> {
    let device = validated_device();
    let scene = Scene::load("teapot").expect("assets/scenes/teapot.toml");
    let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
    let eye = scene.orbit.sample_eye(sample).expect("sample in range");
    let stats = renderer
        .frame(mode, eye, scene.orbit.view(eye))
        .expect("frame");
    assert!(stats.passes.iter().all(|p| p.sample.gpu_ms.is_finite()));
    let pixels = renderer.pixels().expect("read back");
    assert!(
        pixels.iter().flatten().all(|c| c.is_finite()),
        "non-finite pixel"
    );
    pixels
}

#[test]
fn static_em_frame_matches_golden() {
    let pixels = render(FrameMode::StaticEm, 0);
    assert_matches_golden("teapot_static_em_s0", W, H, &pixels, MIN_PSNR_DB);
    assert_no_validation_messages();
}

#[test]
fn static_em_frame_at_last_sample_matches_golden() {
    let scene = Scene::load("teapot").expect("scene");
    let pixels = render(FrameMode::StaticEm, scene.orbit.samples - 1);
    assert_matches_golden("teapot_static_em_last", W, H, &pixels, MIN_PSNR_DB);
    assert_no_validation_messages();
}

#[test]
fn bare_frame_matches_golden() {
    let pixels = render(FrameMode::Bare, 0);
    assert_matches_golden("teapot_bare_s0", W, H, &pixels, MIN_PSNR_DB);
    assert_no_validation_messages();
}

#[test]
fn teapot_reflects_something_and_differs_from_bare() {
    let lit = render(FrameMode::StaticEm, 0);
    let bare = render(FrameMode::Bare, 0);
    assert!(
        engine::compare::psnr(&lit, &bare) < 30.0,
        "modes render the same image"
    );
    // The centre of the frame is the teapot: it must not be black.
    let centre = lit[(H / 2 * W + W / 2) as usize];
    assert!(
        centre[0] + centre[1] + centre[2] > 0.01,
        "teapot centre is black: {centre:?}"
    );
    assert_no_validation_messages();
}
