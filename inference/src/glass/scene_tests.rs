//! The CPU side on the shipped glass scene: shells placed for a far room,
//! the baseline against the greedy paths, tessellation of the real teapot.

use glam::Vec3;

use super::baseline::baseline_mesh;
use super::cluster::{ClusterInput, place_shells};
use super::lens::Lens;
use super::records::exit_ray_hits;
use super::shells::ShellShape;
use super::tessellate::{Screen, TessSettings, tessellate};
use super::{room_box, room_objects};
use crate::scene::Scene;
use crate::trace::SceneBvh;

fn screen(scene: &Scene, eye: Vec3) -> Screen {
    let (width, height) = (160, 120);
    let proj = crate::trace::camera::projection(scene, width, height);
    Screen {
        view_proj: proj * scene.orbit.view(eye),
        width,
        height,
    }
}

#[test]
fn a_glass_teapot_alone_in_the_room_gets_one_box_shell() {
    let scene = Scene::load("glass").expect("shipped glass scene");
    let lens = Lens::new(&scene, "teapot").expect("glass teapot");
    let bvh = SceneBvh::build(&scene);
    let mut rays = Vec::new();
    // Every viewpoint sample together (here: three of them).
    for azimuth in [0.0, 40.0, 80.0] {
        let eye = scene.orbit.eye(azimuth, 0.0);
        let tess = tessellate(&lens, eye, screen(&scene, eye), TessSettings::new(30.0));
        rays.extend(exit_ray_hits(&scene, &bvh, &lens, &tess));
    }
    assert!(rays.len() > 1000, "{} exit rays", rays.len());
    let room = room_objects(&scene);
    let set = place_shells(&ClusterInput {
        origin: lens.mesh.area_weighted_centroid(),
        rays: &rays,
        room_objects: &room,
        room_box: room_box(&scene),
        max_shells: 3,
    });
    assert_eq!(set.shells.len(), 1, "{set:#?}");
    assert!(matches!(set.shells[0].shape, ShellShape::Box { .. }));
    assert_eq!(set.shells[0].objects, room);
}

#[test]
fn baseline_refracts_once_and_greedy_paths_leave_through_the_back() {
    let scene = Scene::load("glass").expect("shipped glass scene");
    let lens = Lens::new(&scene, "teapot").expect("glass teapot");
    let eye = scene.orbit.eye(10.0, 0.0);
    let base = baseline_mesh(&lens, eye);
    let tess = tessellate(&lens, eye, screen(&scene, eye), TessSettings::new(1e6));
    assert_eq!(base.positions.len(), lens.mesh.positions.len());
    assert!(!base.indices.is_empty() && base.indices.len() % 3 == 0);
    // Baseline: one interface, transmitted weight 1 − F, nothing absorbed.
    let mut compared = 0;
    for p in &base.paths {
        assert_eq!(p.t.topology.interfaces, 1);
        if p.t.exited() {
            assert!((p.t.weight.x - p.t.weight.z).abs() < 1e-6);
        }
    }
    // Greedy paths through the real teapot: most refraction paths cross at
    // least two interfaces and lose more red than blue (σ_r > σ_b).
    for p in tess.paths.iter().filter(|p| p.t.exited()) {
        if p.t.topology.interfaces >= 2 && p.t.weight.x > 0.0 {
            assert!(p.t.weight.x < p.t.weight.z, "{:?}", p.t.weight);
            compared += 1;
        }
    }
    assert!(
        compared > tess.paths.len() / 2,
        "{compared} of {}",
        tess.paths.len()
    );
}

#[test]
fn a_teapot_near_the_glass_gets_its_own_layer_in_front_of_the_room() {
    let scene = Scene::load("glass_near").expect("shipped glass_near scene");
    let lens = Lens::new(&scene, "teapot").expect("glass teapot");
    let near = scene
        .objects
        .iter()
        .position(|o| o.name == "near")
        .expect("near object") as u32;
    let set = super::placement::place_for_scene(&scene, &lens, 2);
    assert_eq!(set.shells.len(), 2, "{set:#?}");
    assert_eq!(set.shells[0].objects, vec![near]);
    assert!(!matches!(set.shells[0].shape, ShellShape::Box { .. }));
    assert!(set.shells[0].distance < 1.5, "{}", set.shells[0].distance);
    assert!(matches!(set.shells[1].shape, ShellShape::Box { .. }));
    assert_eq!(set.shells[1].objects, room_objects(&scene));
    // One shell asked for: the room's box holds everything.
    assert_eq!(
        super::placement::place_for_scene(&scene, &lens, 1)
            .shells
            .len(),
        1
    );

    // The layers' maps: the near teapot covers part of the inner one, and
    // the outer one sees the room through it.
    use super::shell_map::{LayerObjects, trace_layer_map};
    let tracer = crate::trace::Tracer::new(&scene).expect("tracer");
    let settings = crate::trace::TraceSettings {
        width: 16,
        height: 96,
        spp: 1,
        ..Default::default()
    };
    let origin = set.origin();
    let inner = trace_layer_map(
        &tracer,
        &LayerObjects {
            hidden: &[lens.object],
            own: Some(&set.shells[0].objects),
        },
        origin,
        16,
        &settings,
    );
    let outer = trace_layer_map(
        &tracer,
        &LayerObjects {
            hidden: &[lens.object, near],
            own: None,
        },
        origin,
        16,
        &settings,
    );
    let covered = inner.iter().filter(|t| t[3] == 1.0).count();
    assert!(
        covered > 0 && covered < inner.len() / 10,
        "{covered} texels"
    );
    assert!(inner.iter().all(|t| t[3] == 0.0 || t[3] == 1.0));
    assert!(
        inner
            .iter()
            .filter(|t| t[3] == 0.0)
            .all(|t| t[..3] == [0.0; 3])
    );
    assert!(
        outer
            .iter()
            .all(|t| t[3] == 1.0 && t.iter().all(|c| c.is_finite()))
    );
    // Where the inner layer is opaque, the outer one shows what is behind.
    let behind = inner
        .iter()
        .zip(&outer)
        .filter(|(i, o)| i[3] == 1.0 && (i[2] - o[2]).abs() > 1e-3)
        .count();
    assert!(behind > covered / 2, "{behind} of {covered}");
}
