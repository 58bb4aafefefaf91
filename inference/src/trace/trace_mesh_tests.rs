//! `mesh.trace_segments`: the tracer sees its own, finer tessellation of a
//! generated surface while the engine draws and solves the coarser one, and
//! the traced images keep the keys of the fine surface (README "Coarser
//! playback tessellation").

use super::SceneBvh;
use super::cache::scene_key;
use crate::scene::{Scene, SceneError};

const TEAPOT_MESH: &str = r#"mesh = { generator = "newell_teapot", segments = 25 }"#;

/// The committed teapot scene with its mesh line replaced by `mesh`.
fn teapot_with(mesh: &str) -> Result<Scene, SceneError> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/scenes/teapot.toml");
    let text = std::fs::read_to_string(path).expect("the committed teapot scene");
    assert!(
        text.contains(TEAPOT_MESH),
        "test bug: the scene's mesh line moved"
    );
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("x.toml");
    std::fs::write(&file, text.replace(TEAPOT_MESH, mesh)).expect("write scene");
    Scene::load(&file.to_string_lossy())
}

fn teapot_segments(segments: u32, trace: Option<u32>) -> Scene {
    let trace = trace.map_or(String::new(), |t| format!(", trace_segments = {t}"));
    let mesh = format!(r#"mesh = {{ generator = "newell_teapot", segments = {segments}{trace} }}"#);
    teapot_with(&mesh).expect("loads")
}

#[test]
fn the_tracer_sees_the_finer_surface_at_the_same_place() {
    let split = teapot_segments(6, Some(12));
    let teapot = split.object("teapot").expect("teapot");
    let fine = teapot.trace_mesh.as_ref().expect("a trace mesh");
    assert!(fine.triangle_count() > 3 * teapot.mesh.triangle_count());
    assert_eq!(teapot.traced_mesh().triangle_count(), fine.triangle_count());
    // Placed alike: the same surface, sampled more finely (bounds within 1 cm).
    let ((lo, hi), (flo, fhi)) = (teapot.mesh.bounds(), fine.bounds());
    assert!(
        lo.abs_diff_eq(flo, 0.01) && hi.abs_diff_eq(fhi, 0.01),
        "{lo} {hi} / {flo} {fhi}"
    );
    // The BVH holds the fine triangles (room, light and all).
    let traced: usize = split
        .objects
        .iter()
        .map(|o| o.traced_mesh().triangle_count())
        .sum();
    let drawn: usize = split.objects.iter().map(|o| o.mesh.triangle_count()).sum();
    assert_eq!(SceneBvh::build(&split).triangle_count(), traced);
    assert_ne!(traced, drawn);
    // Objects without one trace what they draw.
    let floor = split.object("floor").expect("floor");
    assert!(floor.trace_mesh.is_none());
    assert_eq!(floor.traced_mesh().positions, floor.mesh.positions);
}

#[test]
fn traced_images_keep_the_keys_of_the_surface_they_show() {
    let split = teapot_segments(6, Some(12));
    let fine = teapot_segments(12, None);
    let coarse = teapot_segments(6, None);
    assert_eq!(
        scene_key(&split),
        scene_key(&fine),
        "the fine scene's traces are reused"
    );
    assert_ne!(scene_key(&split), scene_key(&coarse));
}

#[test]
fn bad_trace_segments_name_their_field() {
    let zero = r#"mesh = { generator = "newell_teapot", trace_segments = 0 }"#;
    let e = teapot_with(zero).expect_err("0 segments").to_string();
    assert!(
        e.contains("objects[0].mesh.trace_segments") && e.contains("x.toml"),
        "{e}"
    );
    let file = r#"mesh = { obj = "teapot.obj", trace_segments = 8 }"#;
    let e = teapot_with(file).expect_err("a mesh file").to_string();
    assert!(
        e.contains("objects[0].mesh") && e.contains("trace_segments"),
        "{e}"
    );
}
