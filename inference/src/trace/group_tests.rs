//! Reflectors whose boxes touch (lid and body) share their local layers:
//! a ray one reflects that hits the other is a local reflection, and the
//! distant layer passes through both (`Scene::local_group`).

use std::cell::Cell;

use glam::Vec3;

use super::cache::scene_key;
use super::tests::{mean_over, scene, small, sphere};
use super::*;
use crate::scene::{EmSettings, Material, Scene};

/// `a` reflects everything (F ≡ 1), `b` half: what `a` shows of `b` is
/// darker than the white background.
const WHITE: Material = Material::Mirror { f0: Vec3::ONE };
const GREY: Material = Material::Mirror {
    f0: Vec3::splat(0.5),
};

/// Two mirror spheres side by side, touching at the origin, the eye on
/// the orbit (+z); `reflector` says which of them has environment maps.
fn pair(gap: f32, reflector: [bool; 2]) -> Scene {
    let r = 0.3;
    let mut s = scene(vec![
        (
            "a",
            sphere(Vec3::new(-r - gap / 2.0, 0.0, 0.0), r, 48, 96),
            WHITE,
        ),
        (
            "b",
            sphere(Vec3::new(r + gap / 2.0, 0.0, 0.0), r, 48, 96),
            GREY,
        ),
    ]);
    // Close enough that the band of `a` reflecting `b` spans pixels.
    s.orbit.radius = 1.0;
    for (o, em) in s.objects.iter_mut().zip(reflector) {
        o.em = em.then(EmSettings::default);
    }
    s
}

#[test]
fn touching_reflectors_and_only_they_form_a_group() {
    let s = pair(0.0, [true, true]);
    assert_eq!(s.local_group(0), vec![0, 1]);
    assert_eq!(s.local_group(1), vec![0, 1]);
    // Apart, or the other without maps: each alone.
    assert_eq!(pair(0.1, [true, true]).local_group(0), vec![0]);
    assert_eq!(pair(0.0, [true, false]).local_group(0), vec![0]);
    assert_eq!(pair(0.0, [true, false]).local_group(1), vec![1]);
    assert!(s.local_group(7).is_empty());
}

/// Over `a`'s pixels: the mean local coverage, how many are wholly local
/// (α > 0.999), and over those the largest |local − beauty| (F ≡ 1), the
/// largest |distant − 1| (the distant ray passes through `b` to the white
/// background) and the darkest local colour.
fn split_of_a(s: &Scene) -> (f32, u32, [f32; 3]) {
    let tracer = Tracer::new(s).expect("valid");
    let mut settings = small(4);
    (settings.width, settings.height) = (64, 48);
    settings.transport.background = Vec3::ONE;
    let image = tracer
        .render(s.orbit.eye(0.0, 0.0), &settings)
        .expect("render");
    let get = |l: &str, x, y, c| image.layer(l).expect(l).get(64, x, y, c);
    let (fit, past, darkest) = (Cell::new(0.0f32), Cell::new(0.0f32), Cell::new(1.0f32));
    let wholly = Cell::new(0u32);
    let (alpha, n) = mean_over(&image, "a.mask", 1.0, |x, y| {
        let a = get("a.specular_local", x, y, 3);
        if a > 0.999 {
            let local = get("a.specular_local", x, y, 1);
            fit.set(fit.get().max((local - get("beauty", x, y, 1)).abs()));
            past.set(
                past.get()
                    .max((get("a.specular_distant", x, y, 1) - 1.0).abs()),
            );
            darkest.set(darkest.get().min(local));
        }
        wholly.set(wholly.get() + u32::from(a > 0.999));
        a
    });
    assert!(n > 20, "a covers {n} pixels");
    (alpha, wholly.get(), [fit.get(), past.get(), darkest.get()])
}

#[test]
fn a_touching_reflector_is_held_by_the_local_layer() {
    // A sphere never sees itself: alone, its local layer is empty.
    let (alone, ..) = split_of_a(&pair(0.0, [true, false]));
    assert_eq!(alone, 0.0);
    // Beside a touching reflector, the rays that hit it are local ...
    let (grouped, wholly, [fit, past, darkest]) = split_of_a(&pair(0.0, [true, true]));
    assert!(
        grouped > 0.01 && wholly > 3,
        "local coverage {grouped}, {wholly} wholly"
    );
    // ... holding what the beauty shows there (b, darker than the white),
    assert!(fit < 1e-3 && darkest < 0.9, "{fit} {darkest}");
    // and the distant layer sees through b.
    assert!(past < 1e-3, "{past}");
}

#[test]
fn only_scenes_with_a_group_change_their_key() {
    let alone = scene_key(&pair(0.0, [true, false]));
    let grouped = scene_key(&pair(0.0, [true, true]));
    assert!(alone.changes(&grouped).contains(&"local groups".to_owned()));
    // No part of that name unless a group has two members.
    let apart = scene_key(&pair(0.1, [true, true]));
    let apart_ungrouped = scene_key(&pair(0.1, [true, false]));
    assert!(
        !apart
            .changes(&apart_ungrouped)
            .contains(&"local groups".to_owned())
    );
}
