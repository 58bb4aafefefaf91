//! Deferred compositing draws what the papers' multipass draws: on a
//! sample (one map, no blending) and between samples (two maps blended),
//! the two frames agree — the G-buffer's explicit level of detail is the
//! one a forward `texture()` picks, so maps inferred through either path
//! play in both.

mod common;

use common::*;
use engine::compare::psnr;
use engine::pem::player::{Compositing, PemKind, PemSettings};
use engine::pem::source::MapSource;
use engine::renderer::{FrameMode, Renderer};
use inference::scene::Scene;
use std::process::Command;

#[test]
fn deferred_and_multipass_frames_agree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene_path = tiny_scene(dir.path());
    let out = dir.path().join("out");
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
    let device = validated_device();
    let orbit = scene.orbit;
    let frame = |compositing, eye| {
        let mut r = Renderer::new(&device, &scene, 96, 72).expect("renderer");
        let settings = PemSettings {
            compositing,
            ..PemSettings::new(PemKind::Layered)
        };
        let source = MapSource::container(&scene, &out.join("teapot.ptxc")).expect("container");
        r.set_pem(&scene, settings, source).expect("set-up");
        r.frame(FrameMode::Pem, eye, orbit.view(eye))
            .expect("frame");
        r.pixels().expect("pixels")
    };
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
        eprintln!("{what}: deferred against multipass {db:.1} dB");
        assert!(db >= min_db, "{what}: {db:.1} dB");
    }
    assert_no_validation_messages();
}
