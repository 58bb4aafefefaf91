//! The rendering matrix built from probe renders on lavapipe predicts
//! actual renders of random content: `A x` = render(x) to ≥ 140 dB (the
//! issue's aim) for cube maps indexed by texgen and for 2D textures.

mod common;

use common::*;
use engine::probe::VulkanProbe;
use inference::em_geometry::{EmGeometry, texgen};
use inference::probe::{
    Lookup, ProbeGeometry, ProbeRenderer, ProbeSchedule, build_matrix, build_matrix_with,
    verify_matrix,
};
use inference::scene::Scene;
use inference::solve::layout::{TextureLayout, TextureShape};

const W: u32 = 64;
const H: u32 = 48;

fn view_proj(scene: &Scene, sample: u32, w: u32, h: u32) -> (glam::Vec3, glam::Mat4) {
    let eye = scene.orbit.sample_eye(sample).expect("sample");
    let proj = glam::camera::rh::proj::vulkan::perspective(
        scene.camera.fov_y_deg.to_radians(),
        w as f32 / h as f32,
        scene.camera.near,
        scene.camera.far,
    );
    (eye, proj * scene.orbit.view(eye))
}

/// The teapot from orbit sample `sample` at `w × h`, its lookups the
/// distant layer's box texgen, read with `lod_bias`.
fn teapot_box_view(sample: u32, (w, h): (u32, u32), lod_bias: f32) -> ProbeGeometry {
    let scene = Scene::load("teapot").expect("scene");
    let teapot = scene.object("teapot").expect("teapot");
    let (eye, view_proj) = view_proj(&scene, sample, w, h);
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
    ProbeGeometry {
        key: 1,
        positions: teapot.mesh.positions.clone(),
        indices: teapot.mesh.indices.clone(),
        lookup: Lookup::Cube {
            dirs: lookups
                .iter()
                .map(|l| glam::Vec3::new(l[0], l[1], l[2]))
                .collect(),
            lod_bias,
        },
        view_proj,
        width: w,
        height: h,
    }
}

#[test]
fn cube_map_matrix_matches_renders() {
    let device = validated_device();
    let geometry = teapot_box_view(0, (W, H), 0.0);
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
    assert!(sets <= 24);
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

/// The floor of the teapot scene seen from sample 10, textured by its UVs.
fn floor_view() -> ProbeGeometry {
    let scene = Scene::load("teapot").expect("scene");
    let floor = scene.object("floor").expect("floor");
    let (_, view_proj) = view_proj(&scene, 10, W, H);
    ProbeGeometry {
        key: 2,
        positions: floor.mesh.positions.clone(),
        indices: floor.mesh.indices.clone(),
        lookup: Lookup::Uv(floor.mesh.uvs.clone()),
        view_proj,
        width: W,
        height: H,
    }
}

/// A compile switches the probe texture's layout (cube, 2D, other sizes)
/// hundreds of times, more often than a pipeline's descriptor pool holds
/// sets (64): the renderer rebinds its sets in place, and after 70
/// switches of each pipeline's texture a matrix still predicts the renders.
#[test]
fn many_texture_switches_keep_the_matrix_exact() {
    let device = validated_device();
    let cube_view = teapot_box_view(0, (W, H), 0.0);
    let floor = floor_view();
    let cube = |size| TextureLayout::full_chain(TextureShape::Cube { size });
    let flat = |size| {
        TextureLayout::full_chain(TextureShape::Tex2D {
            width: size,
            height: size,
        })
    };
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    for i in 0..70 {
        let size = if i % 2 == 0 { 8 } else { 4 };
        let (c, f) = (cube(size), flat(size));
        let ones = vec![[1.0f32; 4]; c.len()];
        probe.render(&cube_view, &c, &ones).expect("cube render");
        let ones = vec![[1.0f32; 4]; f.len()];
        probe.render(&floor, &f, &ones).expect("2D render");
    }
    let shape = TextureShape::Cube { size: 16 };
    let layout = TextureLayout::full_chain(shape);
    let matrix = build_matrix(&mut probe, &cube_view, &layout, shape, &mut |_, _| {}).expect("A");
    let report = verify_matrix(&mut probe, &cube_view, &layout, &matrix, 5).expect("verify");
    assert!(report.psnr_db >= 140.0, "{report:?}");
    assert_no_validation_messages();
}

#[test]
fn texture_matrix_matches_renders() {
    let device = validated_device();
    let geometry = floor_view();
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

/// The light maps' lookup (the room pass reads the nearest MIP level): its
/// matrix predicts renders as exactly as trilinear's, and every pixel reads
/// one level where trilinear blends two for some.
#[test]
fn nearest_level_matrix_reads_one_level_per_pixel() {
    let device = validated_device();
    let trilinear = floor_view();
    let Some(uvs) = trilinear.lookup.uvs() else {
        panic!("the floor view has 2D lookups");
    };
    let one_level = ProbeGeometry {
        key: trilinear.key + 1,
        lookup: Lookup::UvNearestLevel(uvs.to_vec()),
        ..trilinear.clone()
    };
    let shape = TextureShape::Tex2D {
        width: 16,
        height: 16,
    };
    let layout = TextureLayout::full_chain(shape);
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    // Rows whose weights lie on more than one level.
    let mut two_level_rows = |geometry: &ProbeGeometry| {
        let m = build_matrix(&mut probe, geometry, &layout, shape, &mut |_, _| {}).expect("A");
        let report = verify_matrix(&mut probe, geometry, &layout, &m, 11).expect("verify");
        assert!(report.psnr_db >= 140.0, "{report:?}");
        assert!(m.pixels.len() > 500, "{} rows", m.pixels.len());
        (0..m.pixels.len())
            .filter(|&r| {
                let cols = &m.a.col_idx[m.a.row_ptr[r]..m.a.row_ptr[r + 1]];
                let level = |c: &u32| layout.coords(*c as usize).1;
                cols.iter().any(|c| level(c) != level(&cols[0]))
            })
            .count()
    };
    let blended = two_level_rows(&trilinear);
    assert!(blended > 100, "trilinear blends levels in {blended} rows");
    assert_eq!(two_level_rows(&one_level), 0);
    assert_no_validation_messages();
}

/// The compact schedule (texels 2 apart, every second level) and the
/// thesis's (6 apart, every third) measure the same matrix, bit for bit,
/// in 25 renders instead of 325, with the shipped level-of-detail bias and
/// without; a collision would fail the build instead.
#[test]
fn the_compact_schedule_measures_the_thesis_matrix() {
    let device = validated_device();
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    let shape = TextureShape::Cube { size: 64 };
    let layout = TextureLayout::full_chain(shape);
    for (sample, lod_bias) in [(30, -2.0), (75, 0.0)] {
        let geometry = teapot_box_view(sample, (320, 240), lod_bias);
        let compact = ProbeSchedule::new(&layout, shape);
        let thesis = ProbeSchedule::thesis(&layout, shape);
        let mut build = |schedule: &ProbeSchedule| {
            build_matrix_with(&mut probe, &geometry, &layout, schedule, &mut |_, _| {}).expect("A")
        };
        let (a, b) = (build(&compact), build(&thesis));
        assert_eq!((a.probe_renders, b.probe_renders), (25, 325));
        assert!(a.pixels.len() > 5_000, "{} rows", a.pixels.len());
        assert_eq!(a.pixels, b.pixels);
        assert_eq!(a.a.row_ptr, b.a.row_ptr, "sample {sample}");
        assert_eq!(a.a.col_idx, b.a.col_idx, "sample {sample}");
        let bits = |m: &inference::probe::RenderingMatrix| -> Vec<u32> {
            m.a.values.iter().map(|v| v.to_bits()).collect()
        };
        assert_eq!(bits(&a), bits(&b), "sample {sample}");
        assert!(a.rows_across_faces > 0, "seams are filtered across");
    }
    assert_no_validation_messages();
}
