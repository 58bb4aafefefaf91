//! Reflective materials: mirror geometry, dielectric Fresnel, lossless specular materials
//! in a furnace, glass absorption and its layers.

use glam::Vec3;

use super::tests::{mean_over, quad, scene, small, sphere};
use super::*;

#[test]
fn mirror_rays_land_where_geometry_says() {
    let mirror = Material::Mirror { f0: Vec3::ONE };
    // Plane y = 0 (facing +y) and a sphere of radius 0.5 at (0, 2, 0).
    let s = scene(vec![
        (
            "plane",
            quad(
                Vec3::new(-5.0, 0.0, 5.0),
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, -10.0),
            ),
            mirror.clone(),
        ),
        (
            "ball",
            sphere(Vec3::new(0.0, 2.0, 0.0), 0.5, 256, 512),
            mirror,
        ),
    ]);
    let bvh = SceneBvh::build(&s);
    let integ = Integrator::new(&s, &bvh, Transport::default());

    let (p, r) = integ
        .reflect_once(
            Vec3::new(-1.0, 1.0, 0.3),
            Vec3::new(1.0, -1.0, 0.0).normalize(),
        )
        .expect("hits the plane");
    assert!(p.abs_diff_eq(Vec3::new(0.0, 0.0, 0.3), 1e-5), "{p}");
    assert!(
        r.abs_diff_eq(Vec3::new(1.0, 1.0, 0.0).normalize(), 1e-5),
        "{r}"
    );

    // Straight down onto the sphere's top: back up.
    let (p, r) = integ
        .reflect_once(Vec3::new(0.0, 4.0, 0.0), -Vec3::Y)
        .expect("top");
    assert!((p.y - 2.5).abs() < 1e-4, "{p}");
    assert!(r.abs_diff_eq(Vec3::Y, 1e-3), "{r}");

    // An off-axis ray: angle of incidence equals angle of reflection about (p − c)/R.
    let c = Vec3::new(0.0, 2.0, 0.0);
    let d = Vec3::new(0.2, 0.0, -1.0).normalize();
    let (p, r) = integ
        .reflect_once(Vec3::new(-0.6, 2.1, 3.0), d)
        .expect("side");
    let n = (p - c).normalize();
    assert!(((p - c).length() - 0.5).abs() < 1e-3);
    let expected = d - 2.0 * d.dot(n) * n;
    assert!(r.abs_diff_eq(expected, 2e-3), "{r} vs {expected}");
}

#[test]
fn dielectric_fresnel_is_f0_head_on_and_one_at_grazing() {
    let f0 = ((1.5f32 - 1.0) / 2.5).powi(2);
    let (f, t) = shading_dielectric(1.5, 1.0, true);
    assert!((f - f0).abs() < 1e-6 && t.is_some());
    let (f, _) = shading_dielectric(1.5, std::f32::consts::FRAC_PI_2.cos(), true);
    assert!((f - 1.0).abs() < 1e-5);
    let (f, _) = shading_dielectric(1.5, 0.0, true);
    assert_eq!(f, 1.0);
    // Inside, beyond the critical angle: total internal reflection.
    assert_eq!(shading_dielectric(1.5, 0.3, false), (1.0, None));
    for e in [f32::NAN, 0.0, -1.0, f32::INFINITY] {
        assert!(shading_dielectric(e, 0.5, true).0.is_finite());
    }
    assert!(optics::phong_exponent(0.0).is_finite() && optics::phong_exponent(1.0) >= 1.0);
}

fn shading_dielectric(ior: f32, cos: f32, front: bool) -> (f32, Option<f32>) {
    optics::dielectric_for_tests(ior, cos, front)
}

#[test]
fn axis_aligned_rays_hit_even_with_negative_zero_components() {
    // Rays parallel to box faces, with −0.0 components as `-Vec3::Y` has.
    let s = scene(vec![(
        "plane",
        quad(
            Vec3::new(-5.0, 0.0, 5.0),
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -10.0),
        ),
        Material::Mirror { f0: Vec3::ONE },
    )]);
    let bvh = SceneBvh::build(&s);
    for d in [
        Vec3::new(0.0, -1.0, 0.0),
        -Vec3::Y,
        Vec3::new(-0.0, -1.0, 0.0),
    ] {
        for o in [Vec3::new(0.001, 4.0, 0.0013), Vec3::new(0.5, 4.0, 0.7)] {
            let hit = bvh.closest(o, d, 0.0, f32::INFINITY, None);
            assert!(hit.is_some_and(|h| (h.t - 4.0).abs() < 1e-5), "{o} {d}");
            assert!(bvh.occluded(o, d, 0.0, 10.0), "{o} {d}");
        }
    }
}

/// Mean of `layer` channel `c` over pixels fully covered by object `object`.
fn covered_mean(image: &TraceImage, object: &str, layer: &str, c: usize) -> f32 {
    let l = image.layer(layer).expect("layer");
    let (mean, n) = mean_over(image, &format!("{object}.mask"), 1.0, |x, y| {
        l.get(image.width, x, y, c)
    });
    assert!(n > 50, "{object} covers the frame centre ({n} pixels)");
    mean
}

#[test]
fn lossless_specular_materials_conserve_a_uniform_environment() {
    // In a white furnace, F0 = 1 glossy and clear glass neither gain nor lose energy.
    for material in [
        Material::Glossy {
            f0: Vec3::ONE,
            roughness: 0.5,
        },
        Material::Glass {
            ior: 1.5,
            absorption: Vec3::ZERO,
        },
    ] {
        let s = scene(vec![(
            "ball",
            sphere(Vec3::ZERO, 0.5, 48, 96),
            material.clone(),
        )]);
        let tracer = Tracer::new(&s).expect("valid");
        let mut settings = small(8);
        settings.transport.background = Vec3::ONE;
        let image = tracer
            .render(s.orbit.eye(0.0, 0.0), &settings)
            .expect("render");
        let b = covered_mean(&image, "ball", "beauty", 1);
        assert!((b - 1.0).abs() < 0.02, "{material:?}: {b}");
    }
}

#[test]
fn glass_absorbs_per_channel_and_its_layers_recombine() {
    let s = scene(vec![(
        "ball",
        sphere(Vec3::ZERO, 0.5, 48, 96),
        Material::Glass {
            ior: 1.5,
            absorption: Vec3::new(0.0, 1.0, 4.0),
        },
    )]);
    let tracer = Tracer::new(&s).expect("valid");
    let names = tracer.layer_names();
    assert!(names.iter().any(|n| n == "ball.transmission"), "{names:?}");
    let mut settings = small(8);
    settings.transport.background = Vec3::ONE;
    let image = tracer
        .render(s.orbit.eye(0.0, 0.0), &settings)
        .expect("render");
    let [r, g, b] = [0, 1, 2].map(|c| covered_mean(&image, "ball", "beauty", c));
    assert!(r > 0.97 && g < r && b < g, "{r} {g} {b}");
    // A sphere never reflects itself: beauty = F·distant + transmission per pixel.
    let get = |l: &str, x, y, c| image.layer(l).expect(l).get(32, x, y, c);
    let (err, _) = mean_over(&image, "ball.mask", 1.0, |x, y| {
        assert_eq!(get("ball.specular_local", x, y, 3), 0.0);
        let recombined = get("ball.fresnel", x, y, 2) * get("ball.specular_distant", x, y, 2)
            + get("ball.transmission", x, y, 2);
        (recombined - get("beauty", x, y, 2)).abs()
    });
    assert!(err < 1e-3, "{err}");
}
