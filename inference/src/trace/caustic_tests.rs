//! Caustics: light that reaches a diffuse surface only through a mirror, against the
//! irradiance of the light's mirror image; counted once; the photon map's settings.

use glam::Vec3;

use super::tests::{quad, scene, small, teapot};
use super::*;
use crate::scene::AreaLight;

const RADIANCE: f32 = 10.0;

/// A white patch 1 m up, a mirror on the ground below it and a light 2 m up beside it,
/// facing down: the patch's underside cannot see the light, only its mirror image.
fn mirror_room() -> Scene {
    let light = AreaLight {
        name: "light".into(),
        center: Vec3::new(1.5, 2.0, 0.0),
        edge_u: Vec3::X,
        edge_v: Vec3::Z,
        radiance: Vec3::splat(RADIANCE),
    };
    let mut s = scene(vec![
        (
            "mirror",
            quad(
                Vec3::new(0.0, 0.0, 0.5),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, -1.0),
            ),
            Material::Mirror { f0: Vec3::ONE },
        ),
        (
            "patch",
            quad(
                Vec3::new(-0.5, 1.0, -0.5),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
            ),
            Material::Diffuse {
                albedo: Vec3::ONE,
                texture: None,
            },
        ),
        (
            "light",
            light.mesh(),
            Material::Emissive {
                radiance: light.radiance,
            },
        ),
    ]);
    s.lights.push(light);
    s
}

/// Radiance of a white Lambertian point `p` facing down, lit by the light's image in the
/// ground mirror (F = 1): E/π, E by a 400² midpoint rule over the image.
fn expected(s: &Scene, p: Vec3) -> f32 {
    let l = &s.lights[0];
    let n = 400;
    let da = l.area() / (n * n) as f32;
    let mut e = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let q = l.center
                + ((i as f32 + 0.5) / n as f32 - 0.5) * l.edge_u
                + ((j as f32 + 0.5) / n as f32 - 0.5) * l.edge_v;
            let v = Vec3::new(q.x, -q.y, q.z) - p;
            let r2 = v.length_squared();
            // cos at p (normal −y) and at the image (normal +y) are both −v.y / r.
            let cos = -v.y / r2.sqrt();
            e += f64::from(cos * cos / r2 * da);
        }
    }
    RADIANCE * e as f32 / std::f32::consts::PI
}

fn transport(caustics: Caustics, max_diffuse_bounces: u32) -> Transport {
    Transport {
        max_diffuse_bounces,
        caustics,
        ..Transport::default()
    }
}

/// Mean green radiance of `n` samples of the ray from just under the patch up to `p`.
fn seen_from_below(integrator: &Integrator, p: Vec3, n: u32) -> f32 {
    let (mut sum, mut rays) = (0.0f64, 0u64);
    for s in 0..n {
        let mut rng = rng::Rng::new(5, 0, s, 0);
        let mut distant = rng::Rng::new(5, 0, s, 1);
        let sample = integrator.sample(
            p - Vec3::Y * 0.5,
            Vec3::Y,
            &mut rng,
            &mut distant,
            &mut rays,
        );
        assert_eq!(sample.object, Some(1), "the ray hits the patch");
        sum += f64::from(sample.beauty.y);
    }
    (sum / f64::from(n)) as f32
}

#[test]
fn light_through_a_mirror_reaches_a_shadowed_patch() {
    let s = mirror_room();
    let bvh = SceneBvh::build(&s);
    let points = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(-0.1, 1.0, -0.1)];
    // Photon map: 1.2M paths, r = 0.15 m put ~20k photons under the kernel; over seeds
    // the estimate spreads by σ ≈ 1% (measured: 1.4% at 600k paths).
    let photons = Caustics::Photons {
        photons: 1_200_000,
        radius: 0.15,
    };
    let map = PhotonMap::build(
        &Integrator::new(&s, &bvh, transport(photons, 0)),
        1_200_000,
        0.15,
        0,
    );
    let at = |caustics, bounces, p, n| {
        let integrator = Integrator::new(&s, &bvh, transport(caustics, bounces));
        let map = matches!(caustics, Caustics::Photons { .. }).then_some(&map);
        seen_from_below(&integrator.with_photons(map), p, n)
    };
    for p in points {
        let want = expected(&s, p);
        assert!(want > 0.05, "{want}");
        // Without caustics the underside is black: the light only reaches it by the mirror.
        assert_eq!(at(Caustics::Off, 1, p, 64), 0.0);
        // No bounce: the photon map alone (lookups draw no random numbers).
        let got = at(photons, 0, p, 1);
        assert!(
            (got / want - 1.0).abs() < 0.04,
            "photons at {p}: {got} vs {want}"
        );
    }
    // One bounce, counted by the emitter it finds through the mirror: hit probability
    // ≈ 2.5%, so 400k samples give σ ≈ 1%.
    let p = points[0];
    let want = expected(&s, p);
    let got = at(Caustics::Paths, 1, p, 400_000);
    assert!((got / want - 1.0).abs() < 0.04, "paths: {got} vs {want}");

    // Counted once: with a bounce, photon-map paths also gather the patch's caustic seen
    // in the mirror (+3.6%), which path counting finds one bounce later. Were the emitter
    // found through the mirror also counted on photon-map paths, they would be ~2× apart;
    // both noises (≈ 1% each) and the interreflection's own sampling fit well inside 8%.
    let photons_0 = at(photons, 0, p, 1);
    let photons_1 = at(photons, 1, p, 100_000);
    let paths_2 = at(Caustics::Paths, 2, p, 400_000);
    assert!(
        photons_1 > photons_0 * 1.02,
        "the interreflection adds light: {photons_1} vs {photons_0}"
    );
    assert!(
        (photons_1 / paths_2 - 1.0).abs() < 0.08,
        "photons {photons_1} vs paths {paths_2}"
    );
}

#[test]
fn the_floor_holds_the_teapots_caustic_in_every_layer_that_sees_it() {
    let s = teapot();
    let tracer = Tracer::new(&s).expect("valid");
    let eye = tracer.sample_eye(0).expect("eye");
    let mut off = small(4);
    off.transport.caustics = Caustics::Off;
    let on = small(4);
    let a = tracer.render(eye, &off).expect("off");
    let b = tracer.render(eye, &on).expect("on");
    // Same camera paths: the photon map only adds light, to the floor and to what the
    // teapot reflects of it.
    for layer in ["floor.diffuse", "teapot.specular_distant"] {
        let (la, lb) = (a.layer(layer).expect(layer), b.layer(layer).expect(layer));
        let (sa, sb): (f32, f32) = (la.pixels.iter().sum(), lb.pixels.iter().sum());
        assert!(
            la.pixels.iter().zip(&lb.pixels).all(|(x, y)| y >= x),
            "{layer} never loses light"
        );
        assert!(sb > sa * 1.01, "{layer}: {sb} vs {sa} without caustics");
    }
}

#[test]
fn photon_settings_are_checked_and_extremes_stay_finite() {
    let s = teapot();
    let tracer = Tracer::new(&s).expect("valid");
    let eye = tracer.sample_eye(0).expect("eye");
    for (photons, radius) in [(0, 0.03), (1000, 0.0), (1000, f32::NAN), (1000, 1e3)] {
        let mut settings = small(1);
        settings.transport.caustics = Caustics::Photons { photons, radius };
        let e = tracer
            .render(eye, &settings)
            .expect_err("bad photon settings")
            .to_string();
        assert!(e.contains("caustics") && e.contains("photons"), "{e}");
    }
    for (photons, radius) in [(1, 0.03), (20_000, 1e-4), (20_000, 100.0)] {
        let mut settings = small(1);
        settings.transport.caustics = Caustics::Photons { photons, radius };
        let image = tracer.render(eye, &settings).expect("render");
        for l in &image.layers {
            assert!(l.pixels.iter().all(|v| v.is_finite()), "{}", l.name);
        }
    }
    let mut settings = small(1);
    settings.transport.caustics = Caustics::Paths;
    let image = tracer.render(eye, &settings).expect("paths");
    assert!(
        image
            .layers
            .iter()
            .all(|l| l.pixels.iter().all(|v| v.is_finite()))
    );
}

#[test]
fn views_with_the_same_settings_share_one_photon_map() {
    let s = teapot();
    let shared = Tracer::new(&s).expect("valid");
    let settings = small(2);
    let (e0, e1) = (
        shared.sample_eye(0).expect("eye"),
        shared.sample_eye(40).expect("eye"),
    );
    let first = shared.render(e0, &settings).expect("first view");
    let second = shared.render(e1, &settings).expect("second view");
    let fresh = Tracer::new(&s)
        .expect("valid")
        .render(e1, &settings)
        .expect("alone");
    for (a, b) in second.layers.iter().zip(&fresh.layers) {
        assert_eq!(
            a.pixels, b.pixels,
            "{}: the shared map is the same map",
            a.name
        );
    }
    // Only the image that built the map counts its photon rays.
    assert!(second.rays < fresh.rays && first.rays > second.rays / 2);
    // Another seed builds another map.
    let other = TraceSettings {
        seed: 9,
        ..settings
    };
    let reseeded = shared.render(e1, &other).expect("reseeded");
    assert_eq!(
        reseeded.rays,
        Tracer::new(&s)
            .expect("valid")
            .render(e1, &other)
            .expect("alone")
            .rays
    );
}
