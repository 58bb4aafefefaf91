//! The SH basis, the light grid's quadrature and the CPU reference relight.

use glam::Vec3;

use super::grid::{LightGrid, direction, gauss_legendre};
use super::sh::{self, MAX_K};
use super::*;
use crate::scene::Scene;

/// Scattered unit directions, poles and axes included.
fn directions() -> Vec<Vec3> {
    let mut v = vec![
        Vec3::Y,
        -Vec3::Y,
        Vec3::X,
        -Vec3::Z,
        Vec3::new(1.0, 1.0, 1.0).normalize(),
    ];
    for i in 0..40 {
        let (e, a) = (
            -85.0 + 170.0 * ((i * 7) % 40) as f32 / 40.0,
            9.0 * i as f32 + 3.0,
        );
        v.push(direction(e, a));
    }
    v
}

#[test]
fn gauss_legendre_integrates_polynomials_exactly() {
    let (x, w) = gauss_legendre(5);
    assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-12);
    // Degree 8 ≤ 2·5 − 1: ∫ x⁸ = 2/9.
    let i: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(8)).sum();
    assert!((i - 2.0 / 9.0).abs() < 1e-12, "{i}");
}

#[test]
fn sh_basis_is_orthonormal_by_quadrature() {
    for (rings, azimuths) in [(5, 9), grid::DEFAULT_GRID] {
        let g = LightGrid::new(rings, azimuths);
        assert!((g.weights.iter().sum::<f32>() - 4.0 * std::f32::consts::PI).abs() < 1e-4);
        let ys: Vec<[f32; MAX_K]> = g
            .directions
            .iter()
            .map(|d| {
                let mut y = [0.0; MAX_K];
                sh::eval(*d, &mut y);
                y
            })
            .collect();
        for a in 0..MAX_K {
            for b in 0..MAX_K {
                let dot: f32 = ys
                    .iter()
                    .zip(&g.weights)
                    .map(|(y, w)| w * y[a] * y[b])
                    .sum();
                let want = if a == b { 1.0 } else { 0.0 };
                assert!(
                    (dot - want).abs() < 1e-4,
                    "grid {rings}x{azimuths}: <Y{a}, Y{b}> = {dot}"
                );
            }
        }
    }
}

#[test]
fn recurrence_matches_closed_forms_up_to_band_two() {
    for d in directions() {
        let (x, y, z) = (d.x, d.y, d.z);
        let closed = [
            0.282_095,
            -0.488_603 * z,
            0.488_603 * y,
            -0.488_603 * x,
            1.092_548 * x * z,
            -1.092_548 * y * z,
            0.315_392 * (3.0 * y * y - 1.0),
            -1.092_548 * x * y,
            0.546_274 * (x * x - z * z),
        ];
        let (mut a, mut b) = ([0.0f32; MAX_K], [0.0f32; MAX_K]);
        sh::eval_appendix(d, &mut a);
        sh::eval(d, &mut b);
        for i in 0..9 {
            assert!(
                (a[i] - closed[i]).abs() < 2e-5,
                "appendix Y{i}({d}) = {} vs {}",
                a[i],
                closed[i]
            );
        }
        for i in 0..MAX_K {
            assert!(
                (a[i] - b[i]).abs() < 2e-5,
                "fast Y{i}({d}) = {} vs appendix {}",
                b[i],
                a[i]
            );
        }
        // Truncated evaluation fills exactly the requested prefix.
        let mut c = [0.0f32; 9];
        sh::eval(d, &mut c);
        assert_eq!(&c[..], &b[..9]);
    }
    assert_eq!(sh::bands(16), Some(4));
    assert_eq!(sh::bands(10), None);
}

/// Per texel a known band-limited function of L (coefficients from the texel).
fn known(t: usize, i: usize, c: usize) -> f32 {
    ((t * 31 + i * 7 + c * 3) % 17) as f32 / 17.0 - 0.4
}

#[test]
fn projection_of_a_band_limited_function_reconstructs_it_exactly() {
    let panorama = Panorama {
        width: 4,
        height: 2,
    };
    let g = LightGrid::new(5, 9);
    let f: Vec<Vec<Vec3>> = g
        .directions
        .iter()
        .map(|d| {
            let mut y = [0.0; MAX_K];
            sh::eval(*d, &mut y);
            (0..panorama.texels())
                .map(|t| {
                    let v = |c| (0..MAX_K).map(|i| known(t, i, c) * y[i]).sum::<f32>();
                    Vec3::new(v(0), v(1), v(2))
                })
                .collect()
        })
        .collect();
    let maps = ShMaps::project(panorama, MAX_K, &g, &f);
    for t in 0..panorama.texels() {
        for i in 0..MAX_K {
            for c in 0..3 {
                let got = maps.plane(i)[3 * t + c];
                assert!((got - known(t, i, c)).abs() < 1e-4, "C{i} texel {t}: {got}");
            }
        }
    }
    let irradiance = Vec3::new(1.0, 2.0, 0.5);
    for d in directions() {
        let relit = maps.relight_directional(MAX_K, d, irradiance);
        let mut y = [0.0; MAX_K];
        sh::eval(d, &mut y);
        for (t, r) in relit.iter().enumerate() {
            let want = (0..MAX_K).map(|i| known(t, i, 1) * y[i]).sum::<f32>() * irradiance.y;
            assert!(
                (r.y - want).abs() < 1e-3,
                "texel {t} at {d}: {} vs {want}",
                r.y
            );
        }
    }
    // A point light: the same function along S − P, times I/|S − P|².
    let positions: Vec<Vec3> = (0..panorama.texels())
        .map(|t| Vec3::new(t as f32, 0.0, 1.0))
        .collect();
    let s = Vec3::new(0.5, 2.0, -1.0);
    let lit = maps.relight_point(MAX_K, &positions, s, Vec3::splat(3.0));
    for (t, p) in positions.iter().enumerate() {
        let l = s - *p;
        let want =
            maps.relight_directional(MAX_K, l.normalize(), Vec3::ONE)[t] * 3.0 / l.length_squared();
        assert!((lit[t] - want).abs().max_element() < 1e-4, "texel {t}");
    }
}

#[test]
fn traced_panoramas_relight_close_to_the_tracer_at_held_out_directions() {
    let scene = Scene::load("teapot").expect("teapot");
    let mut relit_scene = RelightScene::new(&scene);
    let teapot = scene.objects.iter().position(|o| o.name == "teapot");
    assert_eq!(relit_scene.reflector, [teapot.expect("teapot") as u32]);
    let settings = PanoramaSettings {
        panorama: Panorama {
            width: 32,
            height: 8,
        },
        spp: 1,
        seed: 0,
        bounces: 0,
    };
    // Every ray from inside the room lands on the room's surfaces.
    let positions = relit_scene.positions(settings.panorama);
    assert!(
        positions
            .iter()
            .all(|p| p.y > -1e-3 && p.y < 4.001 && p.x.abs() < 4.001 && p.z.abs() < 4.001)
    );
    let g = LightGrid::new(6, 12);
    let f: Vec<Vec<Vec3>> = g
        .directions
        .iter()
        .map(|d| relit_scene.trace(MovingLight::Directional(*d), &settings))
        .collect();
    let maps = ShMaps::project(settings.panorama, MAX_K, &g, &f);
    let rms = |a: &[Vec3], b: &[Vec3]| {
        (a.iter()
            .zip(b)
            .map(|(x, y)| (*x - *y).length_squared())
            .sum::<f32>()
            / a.len() as f32)
            .sqrt()
    };
    for (e, a) in HELD_OUT_DEG {
        let d = direction(e, a);
        let traced = relit_scene.trace(MovingLight::Directional(d), &settings);
        let mean =
            (traced.iter().map(|v| v.length_squared()).sum::<f32>() / traced.len() as f32).sqrt();
        assert!(mean > 0.01, "the held-out light lights the room");
        let err25 = rms(&maps.relight_directional(25, d, Vec3::ONE), &traced);
        let err1 = rms(&maps.relight_directional(1, d, Vec3::ONE), &traced);
        assert!(err25 < 0.5 * mean, "({e}, {a}): rms {err25} against {mean}");
        assert!(err25 < err1, "more bands help: k=25 {err25}, k=1 {err1}");
    }
}

/// Lid and body as separate reflectors: the panorama, seen from inside the
/// body, passes through both. Before, rays rising from the body's centroid
/// met the lid from below, so the panorama held the lid, not the room.
#[test]
fn a_split_reflector_is_transparent_to_its_panorama() {
    let scene = Scene::load("teapot_split").expect("teapot_split");
    let relit_scene = RelightScene::new(&scene);
    let part = |name: &str| scene.objects.iter().position(|o| o.name == name);
    let (body, lid) = (part("body").expect("body"), part("lid").expect("lid"));
    assert_eq!(relit_scene.reflector, [body as u32, lid as u32]);
    // The lid's box: above the body's centroid, where the room is seen
    // (the box of the whole teapot also holds the floor under it).
    let (lo, hi) = scene.objects[lid].mesh.bounds();
    let (lo, hi) = (lo - 1e-3, hi + 1e-3);
    let panorama = Panorama {
        width: 32,
        height: 16,
    };
    let points = relit_scene.positions(panorama);
    let inside = points
        .iter()
        .filter(|p| p.cmpge(lo).all() && p.cmple(hi).all())
        .count();
    assert_eq!(inside, 0, "{inside} of {} texels see the lid", points.len());
}
