//! Directional and point lights in the tracer: exact Lambertian radiance, the room's
//! box transparent to directional light, other objects casting shadows.

use glam::Vec3;
use std::f32::consts::PI;

use super::tests::{quad, scene};
use super::*;
use crate::scene::{DirectionalLight, PointLight};

const ALBEDO: f32 = 0.6;

/// Direct light only: no bounces, no caustics, black background.
fn direct_only() -> Transport {
    Transport {
        max_diffuse_bounces: 0,
        caustics: Caustics::Off,
        ..Transport::default()
    }
}

/// A 4 m diffuse floor named `floor` (the room's box) at y = 0, plus `extra` objects.
fn floor_scene(extra: Vec<(&str, crate::scene::Mesh, Material)>) -> Scene {
    let mut objects = vec![(
        "floor",
        quad(
            Vec3::new(-2.0, 0.0, 2.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -4.0),
        ),
        Material::Diffuse {
            albedo: Vec3::splat(ALBEDO),
            texture: None,
        },
    )];
    objects.extend(extra);
    scene(objects)
}

/// Radiance seen looking straight down at floor point `(x, 0, z)` from above.
fn floor_radiance(scene: &Scene, x: f32, z: f32) -> Vec3 {
    let bvh = SceneBvh::build(scene);
    let integrator = Integrator::new(scene, &bvh, direct_only());
    let origin = Vec3::new(x, 1.0, z);
    let dir = Vec3::new(0.0, -1.0, 0.0);
    let hit = bvh
        .closest(origin, dir, 0.0, f32::INFINITY, None)
        .expect("the ray hits the floor");
    let mut rng = rng::Rng::new(0, 0, 0, 0);
    let mut rays = 0;
    integrator.radiance_at(hit, dir, 0, &mut rng, &mut rays)
}

fn sun(to_light: Vec3, e: f32) -> DirectionalLight {
    DirectionalLight {
        name: "sun".into(),
        to_light: to_light.normalize(),
        irradiance: Vec3::splat(e),
    }
}

#[test]
fn diffuse_floor_under_a_directional_light_is_albedo_over_pi_e_cos() {
    for deg in [0.0f32, 30.0, 60.0, 85.0] {
        let t = deg.to_radians();
        let mut s = floor_scene(vec![]);
        s.directional_lights
            .push(sun(Vec3::new(t.sin(), t.cos(), 0.0), 2.5));
        let l = floor_radiance(&s, 0.3, -0.2);
        let want = ALBEDO / PI * 2.5 * t.cos();
        assert!(
            (l - Vec3::splat(want)).abs().max_element() < 1e-5 * want.max(1.0),
            "{deg}°: {l} vs {want}"
        );
    }
    // From below the floor: its upper face gets nothing.
    let mut s = floor_scene(vec![]);
    s.directional_lights
        .push(sun(Vec3::new(0.2, -1.0, 0.0), 2.5));
    assert_eq!(floor_radiance(&s, 0.0, 0.0), Vec3::ZERO);
}

#[test]
fn the_room_box_lets_directional_light_through_and_objects_shadow_it() {
    let lid = |name| {
        (
            name,
            quad(
                Vec3::new(-0.5, 0.5, 0.5),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, -1.0),
            ),
            Material::Diffuse {
                albedo: Vec3::ONE,
                texture: None,
            },
        )
    };
    let lit = ALBEDO / PI * 2.0;
    let mut ceiling = floor_scene(vec![lid("ceiling")]);
    ceiling.directional_lights.push(sun(Vec3::Y, 2.0));
    // The probe ray starts at y = 1, above the quad: it would hit it first, so
    // look from just above the floor's plane instead.
    let bvh = SceneBvh::build(&ceiling);
    let integrator = Integrator::new(&ceiling, &bvh, direct_only());
    let probe = |scene_bvh: &SceneBvh, integrator: &Integrator| {
        let (o, d) = (Vec3::new(0.1, 0.2, 0.23), Vec3::new(0.0, -1.0, 0.0));
        let hit = scene_bvh
            .closest(o, d, 0.0, f32::INFINITY, None)
            .expect("floor");
        let (mut rng, mut rays) = (rng::Rng::new(0, 0, 0, 0), 0);
        integrator.radiance_at(hit, d, 0, &mut rng, &mut rays)
    };
    let through = probe(&bvh, &integrator);
    assert!(
        (through.x - lit).abs() < 1e-5,
        "a ceiling does not shadow: {through}"
    );
    let mut blocker = floor_scene(vec![lid("blocker")]);
    blocker.directional_lights.push(sun(Vec3::Y, 2.0));
    let bvh = SceneBvh::build(&blocker);
    let integrator = Integrator::new(&blocker, &bvh, direct_only());
    assert_eq!(probe(&bvh, &integrator), Vec3::ZERO, "an object shadows");
    // Outside the blocker's shadow the floor is lit.
    assert!((floor_radiance(&blocker, 1.5, 1.5).x - lit).abs() < 1e-5);
}

#[test]
fn diffuse_floor_under_a_point_light_falls_off_with_distance_squared() {
    let mut s = floor_scene(vec![]);
    let (i, h, z) = (4.0, 1.5, 0.1);
    s.point_lights.push(PointLight {
        name: "bulb".into(),
        position: Vec3::new(0.0, h, 0.0),
        intensity: Vec3::splat(i),
    });
    for x in [0.0f32, 0.5, 1.2] {
        let d2 = x * x + z * z + h * h;
        let want = ALBEDO / PI * i * (h / d2.sqrt()) / d2;
        let l = floor_radiance(&s, x, z);
        assert!((l.x - want).abs() < 1e-3 * want, "x {x}: {l} vs {want}");
    }
}

#[test]
fn a_dark_sun_leaves_every_pixel_alone_and_a_bright_one_adds_light() {
    let s = super::tests::teapot();
    let settings = super::tests::small(1);
    let render = |scene: &Scene| {
        let tracer = Tracer::new(scene).expect("tracer");
        let eye = tracer.sample_eye(0).expect("eye");
        let image = tracer.render(eye, &settings).expect("render");
        image.layer("beauty").expect("beauty").pixels.clone()
    };
    let plain = render(&s);
    let mut dark = s.clone();
    dark.directional_lights
        .push(sun(Vec3::new(0.3, 1.0, 0.2), 0.0));
    assert_eq!(
        render(&dark),
        plain,
        "a zero-irradiance sun adds exactly nothing"
    );
    let mut lit = s.clone();
    lit.directional_lights
        .push(sun(Vec3::new(0.3, 1.0, 0.2), 1.0));
    let (a, b): (f32, f32) = (plain.iter().sum(), render(&lit).iter().sum());
    assert!(b > a * 1.05, "a sun adds light: {a} vs {b}");
}
