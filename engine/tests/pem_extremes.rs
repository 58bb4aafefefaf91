//! PEM playback at the extremes the issue names, on a tiny compiled
//! scene: eyes exactly on samples (no blend pass) and beyond the orbit's
//! ends (clamped), inside the local ellipsoid, outside the room box,
//! straight above, grazing; a vertex normal of zero length. Every frame
//! must be finite with validation clean.

mod common;

use common::*;
use engine::pem::player::{Compositing, PemKind, PemSettings};
use engine::pem::source::MapSource;
use engine::renderer::{FrameMode, Renderer};
use glam::Vec3;
use inference::scene::{Orbit, Scene};
use std::path::Path;
use std::process::Command;

/// Compiles the maps of `scene_path` into `out` with the main job itself.
fn compile_maps(scene_path: &Path, out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_engine"))
        .args([
            "--scene",
            scene_path.to_str().expect("utf-8"),
            "--size",
            "64x48",
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
}

/// The eyes at the extremes, each with what makes it one.
fn extreme_eyes(scene: &Scene, centroid: Vec3) -> [(&'static str, Vec3); 10] {
    let orbit = scene.orbit.clone();
    let (room_min, room_max) = scene.bounds();
    [
        ("first sample", orbit.sample_eye(0).expect("sample")),
        (
            "last sample",
            orbit.sample_eye(orbit.samples - 1).expect("sample"),
        ),
        (
            "before the first sample",
            orbit.eye(orbit.start_deg - 30.0, 0.0),
        ),
        (
            "beyond the last sample",
            orbit.eye(orbit.start_deg + 170.0, 0.0),
        ),
        (
            "between samples",
            orbit.eye(orbit.start_deg + 0.5 * orbit.step_deg, 0.0),
        ),
        ("above the plane", orbit.eye(orbit.start_deg, 60.0)),
        ("straight above", orbit.center + Vec3::Y * 2.0),
        (
            "inside the local ellipsoid",
            centroid + Vec3::new(0.01, 0.02, 0.0),
        ),
        ("outside the room box", room_max + Vec3::splat(1.0)),
        ("grazing the floor", Vec3::new(0.0, room_min.y + 1e-4, 2.0)),
    ]
}

/// One PEM frame from `eye`: finite pixels, a blend of valid samples whose
/// weights sum to one, and the passes `settings` call for.
fn assert_extreme_frame(
    renderer: &mut Renderer,
    settings: PemSettings,
    orbit: &Orbit,
    (what, eye): (&str, Vec3),
) {
    let kind = (settings.kind, settings.compositing);
    let stats = renderer
        .frame(FrameMode::Pem, eye, orbit.view(eye))
        .unwrap_or_else(|e| panic!("{kind:?} {what}: {e}"));
    let pixels = renderer.pixels().expect("pixels");
    assert!(
        pixels.iter().flatten().all(|v| v.is_finite()),
        "{kind:?} {what}: non-finite pixel"
    );
    let names: Vec<&str> = stats.passes.iter().map(|p| p.name.as_str()).collect();
    let blend = renderer.pem_blend(eye).expect("PEM set up");
    assert!(
        blend.indices().all(|s| s < orbit.samples),
        "{what}: {blend:?}"
    );
    let sum: f32 = blend.samples.iter().map(|s| s.1).sum();
    assert!((sum - 1.0).abs() < 1e-5, "{what}: {blend:?}");
    if settings.deferred() {
        // One G-buffer pass and one compositing pass, however many samples.
        assert!(
            names.contains(&"pem_gbuffer") && names.contains(&"pem_composite"),
            "{names:?}"
        );
        assert!(!names.contains(&"pem_blend"), "{names:?}");
    } else {
        // A blend pass exactly when the eye is between two samples.
        assert_eq!(
            names.contains(&"pem_blend"),
            blend.samples.len() > 1,
            "{what}: {names:?}"
        );
    }
    if what.contains("sample") && !what.contains("between") {
        assert_eq!(blend.samples.len(), 1, "{what}: {blend:?}");
    }
}

#[test]
fn pem_frames_stay_finite_at_the_extremes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene_path = tiny_scene(dir.path());
    let out = dir.path().join("out");
    compile_maps(&scene_path, &out);

    let mut scene = Scene::load(scene_path.to_str().expect("utf-8")).expect("scene");
    let teapot = scene
        .objects
        .iter_mut()
        .find(|o| o.name == "teapot")
        .expect("teapot");
    teapot.mesh.normals[0] = Vec3::ZERO; // a vertex normal of zero length
    let centroid = teapot.mesh.area_weighted_centroid();
    let device = validated_device();
    let mut renderer = Renderer::new(&device, &scene, 64, 48).expect("renderer");
    let orbit = scene.orbit.clone();
    let eyes = extreme_eyes(&scene, centroid);
    let multipass = PemSettings {
        compositing: Compositing::Multipass,
        ..PemSettings::new(PemKind::Layered)
    };
    for settings in [
        PemSettings::new(PemKind::Layered),
        multipass,
        PemSettings::new(PemKind::Ptm),
    ] {
        let source = MapSource::container(&scene, &out.join("teapot.ptxc")).expect("container");
        renderer
            .set_pem(&scene, settings, source)
            .expect("PEM set-up");
        for eye in eyes {
            assert_extreme_frame(&mut renderer, settings, &orbit, eye);
        }
    }
    assert_no_validation_messages();
}
