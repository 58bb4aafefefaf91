//! Tests of the shells: lookups, LBG placement, the targets' confidence.

use glam::Vec3;

use super::cluster::{ClusterInput, Intersection, lbg, place_shells};
use super::shells::ShellShape;
use super::targets::confidence;

#[test]
fn shell_lookups_from_inside_outside_and_parallel() {
    let o = Vec3::new(0.0, 1.0, 0.0);
    let sphere = ShellShape::Sphere { radius: 2.0 };
    let l = sphere.lookup(o, o + Vec3::X * 0.5, Vec3::X);
    assert!(l.abs_diff_eq(Vec3::X * 2.0, 1e-5), "{l}");
    // Outside, pointing away: a miss, the direction itself.
    assert_eq!(sphere.lookup(o, o + Vec3::X * 5.0, Vec3::X), Vec3::X);
    let cylinder = ShellShape::Cylinder {
        radius: 3.0,
        half_height: 1.0,
    };
    let side = cylinder.lookup(o, o, Vec3::Z);
    assert!(side.abs_diff_eq(Vec3::Z * 3.0, 1e-5), "{side}");
    let cap = cylinder.lookup(o, o, Vec3::Y);
    assert!(cap.abs_diff_eq(Vec3::Y, 1e-5), "{cap}");
    let slanted = cylinder.lookup(o, o, Vec3::new(1.0, 1.0, 0.0).normalize());
    assert!((slanted.y - 1.0).abs() < 1e-5 && (slanted.x - 1.0).abs() < 1e-5);
    let quad = ShellShape::Quad {
        center: [0.0, 1.0, -4.0],
        normal: [0.0, 0.0, 1.0],
        u: [1.0, 0.0, 0.0],
        half: [1.0, 1.0],
    };
    let hit = quad.lookup(o, o, Vec3::NEG_Z);
    assert!(hit.abs_diff_eq(Vec3::NEG_Z * 4.0, 1e-5));
    // Parallel to the plane and away from it: far along the plane.
    for d in [Vec3::X, Vec3::new(0.3, 0.0, 1.0).normalize()] {
        let far = quad.lookup(o, o, d);
        assert!(far.is_finite() && far.length() > 100.0, "{d} -> {far}");
    }
    let room = ShellShape::Box {
        min: [-4.0, 0.0, -4.0],
        max: [4.0, 4.0, 4.0],
    };
    let floor = room.lookup(o, o + Vec3::X, Vec3::NEG_Y);
    assert!(
        floor.abs_diff_eq(Vec3::new(1.0, -1.0, 0.0), 1e-5),
        "{floor}"
    );
    assert_eq!(ShellShape::Infinity.lookup(o, o, Vec3::Y), Vec3::Y);
    for shape in [sphere, cylinder, quad, room, ShellShape::Infinity] {
        for d in [Vec3::ZERO, Vec3::splat(f32::NAN), Vec3::X] {
            assert!(shape.lookup(o, o, d).is_finite(), "{shape:?} {d}");
        }
    }
}

#[test]
fn lbg_separates_two_groups_of_distances() {
    let mut values: Vec<f32> = (0..50).map(|i| 0.5 + 0.002 * i as f32).collect();
    values.extend((0..200).map(|i| 4.0 + 0.01 * i as f32));
    let means = lbg(&values, 2);
    assert_eq!(means.len(), 2);
    assert!(
        (means[0] - 0.549).abs() < 0.01 && (means[1] - 4.995).abs() < 0.01,
        "{means:?}"
    );
    assert_eq!(lbg(&values, 1).len(), 1);
    assert!(lbg(&[], 3).is_empty());
    assert_eq!(
        lbg(&[2.0; 10], 3),
        vec![2.0],
        "identical values: one cluster"
    );
}

fn hit(object: u32, point: Vec3) -> Intersection {
    Intersection { object, point }
}

#[test]
fn shells_take_whole_objects_and_the_room_is_one_box() {
    // Object 5 (a cup) stands near the lens; objects 0-2 are the room. The
    // floor also has near hits, but it stays with the room.
    let origin = Vec3::new(0.0, 0.3, 0.0);
    let mut rays = Vec::new();
    for i in 0..40 {
        let x = -0.2 + 0.01 * i as f32;
        rays.push(vec![
            hit(5, Vec3::new(x, 0.3, 0.6)),
            hit(1, Vec3::new(x, 1.0, 4.0)),
        ]);
        rays.push(vec![hit(1, Vec3::new(4.0, 1.0, x))]);
        rays.push(vec![hit(2, Vec3::new(x * 3.0, 3.0, x))]);
    }
    for i in 0..10 {
        rays.push(vec![hit(0, Vec3::new(0.1 * i as f32, 0.0, 0.3))]);
    }
    let room_box = (Vec3::new(-4.0, 0.0, -4.0), Vec3::new(4.0, 4.0, 4.0));
    let input = ClusterInput {
        origin,
        rays: &rays,
        room_objects: &[0, 1, 2],
        room_box,
        max_shells: 3,
    };
    let set = place_shells(&input);
    assert_eq!(set.shells.len(), 2, "{set:#?}");
    assert_eq!(set.shells[0].objects, vec![5]);
    assert!(
        matches!(set.shells[0].shape, ShellShape::Quad { .. }),
        "narrow cone"
    );
    assert!((set.shells[0].distance - 0.6).abs() < 0.05);
    assert_eq!(set.shells[1].objects, vec![0, 1, 2]);
    assert!(matches!(set.shells[1].shape, ShellShape::Box { .. }));
    assert_eq!((set.channels(0), set.channels(1)), (4, 3));
    // Only the room: one shell whatever the maximum.
    let room_only: Vec<_> = rays.iter().filter(|r| r[0].object != 5).cloned().collect();
    let one = place_shells(&ClusterInput {
        rays: &room_only,
        ..input.clone()
    });
    assert_eq!(one.shells.len(), 1);
    // Objects all around the lens at one height: a cylinder.
    let ring: Vec<Vec<Intersection>> = (0..36)
        .map(|i| {
            let a = (i as f32 * 10.0).to_radians();
            vec![hit(
                7,
                origin + Vec3::new(a.cos() * 2.0, 0.2, a.sin() * 2.0),
            )]
        })
        .collect();
    let set = place_shells(&ClusterInput {
        rays: &ring,
        room_objects: &[],
        max_shells: 1,
        ..input
    });
    assert!(
        matches!(set.shells[0].shape, ShellShape::Cylinder { radius, .. } if (radius - 2.0).abs() < 1e-3),
        "{set:?}"
    );
}

#[test]
fn confidence_falls_to_zero_at_five_degrees() {
    let a = Vec3::Z;
    let tilt = |deg: f32| Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
    assert_eq!(confidence(&[a, a, a]), 1.0);
    assert_eq!(confidence(&[a]), 1.0);
    assert!((confidence(&[a, tilt(2.5)]) - 0.75).abs() < 1e-3);
    assert_eq!(confidence(&[a, tilt(1.0), tilt(6.0)]), 0.0);
}

#[test]
fn traced_targets_hold_each_terms_weight_per_pixel() {
    use super::{Lens, room_box_shape, room_shell, targets};
    use crate::scene::Scene;
    use crate::trace::{TraceSettings, Tracer};
    let scene = Scene::load("glass").expect("built-in glass scene");
    let lens = Lens::new(&scene, "teapot").expect("glass teapot");
    let origin = lens.mesh.area_weighted_centroid();
    let shells = room_shell(&scene, origin, room_box_shape(&scene));
    let tracer = Tracer::new(&scene).expect("tracer");
    let settings = TraceSettings {
        width: 32,
        height: 24,
        spp: 2,
        ..TraceSettings::default()
    };
    let eye = scene.orbit.eye(30.0, 0.0);
    let t = targets::trace_targets(&tracer, &lens, &shells, eye, &settings);
    let n = (settings.width * settings.height) as usize;
    assert_eq!((t.t.weight.len(), t.r.weight.len()), (n, n));
    let mut on_lens = 0;
    for p in 0..n {
        let (wt, wr) = (t.t.weight[p], t.r.weight[p]);
        for c in 0..3 {
            // F and 1 − F split the light; absorption only takes away.
            assert!(wt[c] >= 0.0 && wr[c] >= 0.0, "pixel {p}: {wt:?} {wr:?}");
            assert!(wt[c] + wr[c] <= 1.0 + 1e-5, "pixel {p}: {wt:?} {wr:?}");
        }
        if t.coverage[p] == 0.0 {
            assert_eq!((wt, wr), ([0.0; 3], [0.0; 3]), "pixel {p} misses the lens");
        } else if t.coverage[p] == 1.0 {
            on_lens += 1;
        }
    }
    assert!(on_lens > 20, "{on_lens} pixels wholly on the lens");
    // Clear glass: the refraction term carries most of the light.
    let mean = |w: &[[f32; 3]]| w.iter().map(|v| v[1]).sum::<f32>() / w.len() as f32;
    assert!(mean(&t.t.weight) > 2.0 * mean(&t.r.weight));
}
