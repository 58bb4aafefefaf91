//! The rendering matrix built from probe renders on lavapipe predicts
//! actual renders of random content: `A x` = render(x) to ≥ 140 dB (the
//! issue's aim) for cube maps indexed by texgen and for 2D textures.

mod common;

use common::*;
use engine::probe::VulkanProbe;
use inference::em_geometry::{EmGeometry, texgen};
use inference::probe::{Lookup, ProbeGeometry, build_matrix, verify_matrix};
use inference::scene::Scene;
use inference::solve::layout::{TextureLayout, TextureShape};

const W: u32 = 64;
const H: u32 = 48;

fn view_proj(scene: &Scene, sample: u32) -> (glam::Vec3, glam::Mat4) {
    let eye = scene.orbit.sample_eye(sample).expect("sample");
    let proj = glam::camera::rh::proj::vulkan::perspective(
        scene.camera.fov_y_deg.to_radians(),
        W as f32 / H as f32,
        scene.camera.near,
        scene.camera.far,
    );
    (eye, proj * scene.orbit.view(eye))
}

#[test]
fn cube_map_matrix_matches_renders() {
    let device = validated_device();
    let scene = Scene::load("teapot").expect("scene");
    let teapot = scene.object("teapot").expect("teapot");
    let (eye, view_proj) = view_proj(&scene, 0);
    let (lo, hi) = scene.bounds();
    let origin = teapot.mesh.area_weighted_centroid();
    let mut lookups = vec![[0.0; 4]; teapot.mesh.positions.len()];
    texgen(
        &EmGeometry::Box { min: lo, max: hi },
        origin,
        eye,
        &teapot.mesh.positions,
        &teapot.mesh.normals,
        &mut lookups,
    );
    let geometry = ProbeGeometry {
        key: 1,
        positions: teapot.mesh.positions.clone(),
        indices: teapot.mesh.indices.clone(),
        lookup: Lookup::Cube {
            dirs: lookups
                .iter()
                .map(|l| glam::Vec3::new(l[0], l[1], l[2]))
                .collect(),
            lod_bias: 0.0,
        },
        view_proj,
        width: W,
        height: H,
    };
    let shape = TextureShape::Cube { size: 16 };
    let layout = TextureLayout::full_chain(shape);
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    let matrix = build_matrix(&mut probe, &geometry, &layout, shape, &mut |_, _| {}).expect("A");
    assert!(
        matrix.pixels.len() > 200,
        "teapot covers {} pixels",
        matrix.pixels.len()
    );
    // One coverage render plus one per non-empty probe set (a 4x4 level
    // has no texels 4 or 5 apart from the origin, so some sets are empty).
    let sets = inference::probe::ProbeSchedule::new(&layout, shape)
        .sets
        .len();
    assert!(sets <= 3 * 108);
    assert_eq!(matrix.probe_renders as usize, 1 + sets);
    let report = verify_matrix(&mut probe, &geometry, &layout, &matrix, 42).expect("verify");
    eprintln!(
        "A x vs render: {report:?}, {} rows, {} nnz",
        matrix.pixels.len(),
        matrix.a.nnz()
    );
    assert!(report.psnr_db >= 140.0, "{report:?}");
    assert_no_validation_messages();
}

#[test]
fn texture_matrix_matches_renders() {
    let device = validated_device();
    let scene = Scene::load("teapot").expect("scene");
    let floor = scene.object("floor").expect("floor");
    let (_, view_proj) = view_proj(&scene, 10);
    let geometry = ProbeGeometry {
        key: 2,
        positions: floor.mesh.positions.clone(),
        indices: floor.mesh.indices.clone(),
        lookup: Lookup::Uv(floor.mesh.uvs.clone()),
        view_proj,
        width: W,
        height: H,
    };
    let shape = TextureShape::Tex2D {
        width: 16,
        height: 16,
    };
    let layout = TextureLayout::full_chain(shape);
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    let matrix = build_matrix(&mut probe, &geometry, &layout, shape, &mut |_, _| {}).expect("A");
    assert!(matrix.pixels.len() > 500);
    let report = verify_matrix(&mut probe, &geometry, &layout, &matrix, 7).expect("verify");
    eprintln!(
        "A x vs render: {report:?}, {} rows, {} nnz",
        matrix.pixels.len(),
        matrix.a.nnz()
    );
    assert!(report.psnr_db >= 140.0, "{report:?}");
    assert_no_validation_messages();
}
