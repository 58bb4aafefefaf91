//! Rays leaving the lens's convex hull skip their traversal
//! (`Lens::escapes`): the shortcut must never hide a hit and must not
//! change a single path. On the shipped glass teapot, whose spout and
//! handle reach in front of much of the body.

use glam::Vec3;

use super::lens::Lens;
use super::path::vertex_paths;
use super::tessellate::{Screen, TessSettings, tessellate};
use crate::scene::Scene;
use crate::trace::optics::offset;

fn teapot() -> (Scene, Lens) {
    let scene = Scene::load("glass").expect("shipped glass scene");
    let lens = Lens::new(&scene, "teapot").expect("glass teapot");
    (scene, lens)
}

/// A small deterministic generator of numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn dir(&mut self) -> Vec3 {
        let z = 2.0 * self.next() - 1.0;
        let a = std::f32::consts::TAU * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * a.cos(), z, r * a.sin())
    }
}

#[test]
fn a_ray_said_to_escape_meets_nothing() {
    let (_, lens) = teapot();
    let mesh = &lens.mesh;
    let mut rng = Lcg(7);
    let (mut escaped, mut hull_kept, mut off_hull_hits) = (0, 0, 0);
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(t);
        let Some(n) = (b - a).cross(c - a).try_normalize() else {
            continue;
        };
        for _ in 0..3 {
            let (u, v) = (rng.next(), rng.next());
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let p = a + u * (b - a) + v * (c - a);
            let d = rng.dir();
            // Outwards, as a ray leaving the surface is.
            let d = if d.dot(n) < 0.0 { -d } else { d };
            let origin = offset(p, n);
            let hit = lens.closest(origin, d);
            if lens.escapes(t as u32, origin, d) {
                escaped += 1;
                assert!(
                    hit.is_none(),
                    "triangle {t}: the ray from {origin} along {d} escapes but hits {hit:?}"
                );
            } else if lens.on_hull(t as u32) {
                hull_kept += 1;
            } else {
                off_hull_hits += usize::from(hit.is_some());
            }
        }
    }
    let rays = 3 * mesh.triangle_count();
    // Not vacuous: many rays escape, and rays off the hull do meet the lens.
    assert!(escaped > rays / 10, "{escaped} of {rays} rays escape");
    assert!(
        off_hull_hits > rays / 20,
        "{off_hull_hits} rays off the hull hit"
    );
    // Grazing rays and the margin keep a few hull rays traversed.
    assert!(
        hull_kept < escaped,
        "{hull_kept} hull rays kept, {escaped} escaped"
    );
}

#[test]
fn triangles_off_the_hull_never_escape() {
    let (_, lens) = teapot();
    let mesh = &lens.mesh;
    let off: Vec<u32> = (0..mesh.triangle_count() as u32)
        .filter(|&t| !lens.on_hull(t))
        .collect();
    assert!(!off.is_empty() && off.len() < mesh.triangle_count());
    let mut rng = Lcg(11);
    for &t in &off {
        let [a, b, c] = mesh.triangle(t as usize);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let origin = offset((a + b + c) / 3.0, n);
        assert!(!lens.escapes(t, origin, n));
        assert!(!lens.escapes(t, origin, rng.dir()));
    }
    // Out of range: no plane, no shortcut.
    assert!(!lens.escapes(u32::MAX, Vec3::ZERO, Vec3::Y));
}

#[test]
fn paths_are_the_same_with_and_without_the_shortcut() {
    let (scene, lens) = teapot();
    let mesh = &lens.mesh;
    // A triangle holding each vertex, a hull one where there is one.
    let mut on = vec![u32::MAX; mesh.positions.len()];
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        for &v in tri {
            let slot = &mut on[v as usize];
            if *slot == u32::MAX || (lens.on_hull(t as u32) && !lens.on_hull(*slot)) {
                *slot = t as u32;
            }
        }
    }
    let mut compared = 0;
    for (azimuth, elevation) in [(0.0, 0.0), (70.0, 15.0), (200.0, 35.0)] {
        let eye = scene.orbit.eye(azimuth, elevation);
        for v in (0..mesh.positions.len()).step_by(5) {
            let vertex = (mesh.positions[v], mesh.normals[v]);
            let plain = vertex_paths(&lens, eye, vertex, None);
            let short = vertex_paths(&lens, eye, vertex, Some(on[v]));
            assert_eq!(plain, short, "vertex {v} from {eye}");
            compared += 1;
        }
    }
    assert!(compared > 10_000);
}

#[test]
fn tessellated_vertices_lie_on_their_triangles() {
    let (scene, lens) = teapot();
    let eye = scene.orbit.eye(30.0, 10.0);
    let (width, height) = (320, 240);
    let screen = Screen {
        view_proj: crate::trace::camera::projection(&scene, width, height) * scene.orbit.view(eye),
        width,
        height,
    };
    let tess = tessellate(&lens, eye, screen, TessSettings::new(10.0));
    assert!(tess.stats.added_vertices > 0);
    assert_eq!(tess.on.len(), tess.positions.len());
    for (i, (&p, &t)) in tess.positions.iter().zip(&tess.on).enumerate() {
        let [a, b, c] = lens.mesh.triangle(t as usize);
        let n = (b - a).cross(c - a).normalize();
        let distance = n.dot(p - a).abs();
        assert!(distance < 1e-5, "vertex {i}: {distance} m off triangle {t}");
    }
}
