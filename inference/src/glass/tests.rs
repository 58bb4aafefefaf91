//! Tests of the glass CPU side on analytic lenses (a sphere, a box).

use glam::{Mat4, Vec2, Vec3};

use super::lens::Lens;
use super::path::{angle_deg, two_paths, vertex_paths};
use super::shells::{Shell, ShellSet, ShellShape};
use super::tessellate::{Screen, TessSettings, tessellate};
use super::vertices::{stride, vertex_stream};
use crate::scene::Mesh;

/// Triangles wound so their normal points away from `center`.
fn outward(mesh: &mut Mesh, center: Vec3) {
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(t);
        if (b - a).cross(c - a).dot((a + b + c) / 3.0 - center) < 0.0 {
            mesh.indices.swap(3 * t + 1, 3 * t + 2);
        }
    }
}

/// A UV sphere with smooth normals.
pub(super) fn sphere(center: Vec3, radius: f32, rings: u32, segments: u32) -> Mesh {
    let mut m = Mesh::default();
    let mut push = |n: Vec3| {
        m.positions.push(center + n * radius);
        m.normals.push(n);
        m.uvs.push(Vec2::ZERO);
    };
    push(Vec3::Y);
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    push(Vec3::NEG_Y);
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let last = m.positions.len() as u32 - 1;
    for j in 0..segments {
        m.indices.extend([0, ring(1, j), ring(1, j + 1)]);
        m.indices
            .extend([last, ring(rings - 1, j), ring(rings - 1, j + 1)]);
        for i in 1..rings - 1 {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            m.indices.extend([a, c, b, b, c, d]);
        }
    }
    outward(&mut m, center);
    m
}

/// An axis-aligned box, four vertices per face with the face's normal.
pub(super) fn cube(min: Vec3, max: Vec3) -> Mesh {
    let mut m = Mesh::default();
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let mut e1 = Vec3::ZERO;
            let mut e2 = Vec3::ZERO;
            e1[(axis + 1) % 3] = h[(axis + 1) % 3];
            e2[(axis + 2) % 3] = h[(axis + 2) % 3];
            let base = m.positions.len() as u32;
            for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                m.positions.push(c + n * h + e1 * s + e2 * t);
                m.normals.push(n);
                m.uvs.push(Vec2::ZERO);
            }
            m.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    outward(&mut m, c);
    m
}

fn glass(mesh: Mesh, ior: f32, absorption: Vec3) -> Lens {
    Lens::from_mesh(0, mesh, ior, absorption)
}

const F0_15: f32 = 0.04; // ((1.5 − 1)/(1.5 + 1))²

#[test]
fn a_ray_through_the_centre_of_a_sphere_goes_straight_and_absorbs() {
    let sigma = Vec3::new(0.5, 0.1, 0.0);
    let lens = glass(sphere(Vec3::ZERO, 1.0, 48, 96), 1.5, sigma);
    let eye = Vec3::new(0.0, 0.0, 5.0);
    let paths = vertex_paths(&lens, eye, (Vec3::new(0.0, 0.0, 1.0), Vec3::Z), None);
    let t = paths.t;
    assert!(t.exited());
    assert_eq!((t.topology.interfaces, t.topology.choices), (2, 0));
    assert!(angle_deg(t.dir, Vec3::NEG_Z) < 0.5, "{}", t.dir);
    assert!(t.origin.z < -0.99, "leaves at the back: {}", t.origin);
    let expected = (1.0 - F0_15) * (1.0 - F0_15) * (-sigma * 2.0).exp();
    assert!(
        t.weight.abs_diff_eq(expected, 2e-3),
        "{} vs {expected}",
        t.weight
    );
    let r = paths.r;
    assert!(r.exited() && r.topology.interfaces == 1 && r.topology.choices == 1);
    assert!(angle_deg(r.dir, Vec3::Z) < 1e-3);
    assert!((r.weight - Vec3::splat(F0_15)).abs().max_element() < 1e-6);
}

#[test]
fn a_slab_shifts_an_oblique_ray_but_keeps_its_direction() {
    let lens = glass(
        cube(Vec3::new(-2.0, -2.0, -0.1), Vec3::new(2.0, 2.0, 0.1)),
        1.5,
        Vec3::ZERO,
    );
    let p = Vec3::new(0.0, 0.0, 0.1);
    let eye = p + Vec3::new(1.0, 0.0, 1.0) * 3.0;
    let d = (p - eye).normalize();
    let paths = vertex_paths(&lens, eye, (p, Vec3::Z), None);
    assert!(paths.t.exited());
    assert!(angle_deg(paths.t.dir, d) < 1e-3, "{} vs {d}", paths.t.dir);
    // Inside, the ray bends towards the normal: it leaves less far along −x.
    let exit = paths.t.origin;
    assert!(exit.z < -0.099 && exit.x < 0.0 && exit.x > -0.2, "{exit}");
}

#[test]
fn ior_one_has_no_interface() {
    let lens = glass(sphere(Vec3::ZERO, 1.0, 24, 48), 1.0, Vec3::ZERO);
    let eye = Vec3::new(0.3, 0.4, 5.0);
    for (p, n) in lens
        .mesh
        .positions
        .iter()
        .zip(&lens.mesh.normals)
        .step_by(7)
    {
        let d = (*p - eye).normalize();
        let paths = vertex_paths(&lens, eye, (*p, *n), None);
        assert_eq!(paths.r.weight, Vec3::ZERO, "no reflection at {p}");
        if n.dot(d) < 0.0 {
            assert!(paths.t.exited());
            assert_eq!(paths.t.weight, Vec3::ONE);
            assert!(angle_deg(paths.t.dir, d) < 1e-3, "straight through at {p}");
        }
    }
}

#[test]
fn grazing_rays_transmit_nothing_and_stay_finite() {
    let lens = glass(sphere(Vec3::ZERO, 1.0, 24, 48), 1.5, Vec3::splat(0.2));
    // The eye sees the vertex exactly edge-on, and slightly from behind.
    for eye in [Vec3::new(5.0, 1.0, 0.0), Vec3::new(5.0, 1.0001, 0.0)] {
        let paths = vertex_paths(&lens, eye, (Vec3::Y, Vec3::Y), None);
        for path in [paths.t, paths.r] {
            assert!(path.weight.is_finite() && path.dir.is_finite() && path.origin.is_finite());
        }
        assert_eq!(paths.t.weight, Vec3::ZERO);
        assert!(!paths.t.exited());
    }
    // A zero or NaN normal: finite, treated as facing the eye.
    for n in [Vec3::ZERO, Vec3::splat(f32::NAN)] {
        let paths = vertex_paths(&lens, Vec3::new(0.0, 5.0, 0.0), (Vec3::Y, n), None);
        assert!(paths.t.weight.is_finite() && paths.r.dir.is_finite());
    }
}

#[test]
fn total_internal_reflection_everywhere_never_exits() {
    // Inside a glass cube at 45° to its walls (beyond the 41.8° critical
    // angle): every interface reflects totally, the path circles until the
    // bounce limit and contributes nothing.
    let lens = glass(
        cube(Vec3::splat(-1.0), Vec3::splat(1.0)),
        1.5,
        Vec3::splat(0.1),
    );
    let d = Vec3::new(1.0, 1.0, 0.0).normalize();
    // Off the faces' diagonals, so no hit lands on a shared edge.
    let p = Vec3::new(1.0, 0.1, 0.37);
    let s = Lens::vertex_surface(p, Vec3::X, d);
    assert!(!s.front, "seen from inside");
    let paths = two_paths(&lens, &s, d, None);
    assert_eq!(paths.t.weight, Vec3::ZERO, "no refraction out");
    let r = paths.r;
    assert!(!r.exited());
    assert_eq!(u32::from(r.topology.interfaces), lens.max_interfaces);
    assert_eq!(r.weight, Vec3::ZERO);
    assert_eq!(
        r.topology.choices.count_ones(),
        u32::from(r.topology.interfaces)
    );
    assert!(r.origin.is_finite() && r.dir.is_finite());
}

/// The eye, screen and settings of the tessellation tests.
fn view(eye: Vec3) -> Screen {
    let proj = glam::camera::rh::proj::vulkan::perspective(0.7, 4.0 / 3.0, 0.05, 50.0);
    let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y);
    Screen {
        view_proj: proj * view,
        width: 320,
        height: 240,
    }
}

/// True when some vertex lies strictly inside an edge of the mesh.
fn has_t_junction(positions: &[Vec3], indices: &[u32]) -> Option<(u32, u32, usize)> {
    for tri in indices.chunks_exact(3) {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            let len = pa.distance(pb);
            for (i, p) in positions.iter().enumerate() {
                if i as u32 == a || i as u32 == b {
                    continue;
                }
                let (da, db) = (p.distance(pa), p.distance(pb));
                if da > 1e-6 && db > 1e-6 && (da + db - len).abs() < 1e-6 * len.max(1.0) {
                    return Some((a, b, i));
                }
            }
        }
    }
    None
}

#[test]
fn tessellation_splits_where_paths_differ_without_t_junctions() {
    let lens = glass(sphere(Vec3::ZERO, 1.0, 6, 12), 1.5, Vec3::ZERO);
    let eye = Vec3::new(0.5, 1.0, 4.0);
    let coarse = tessellate(&lens, eye, view(eye), TessSettings::new(1e6));
    assert_eq!(
        coarse.stats.added_vertices, 0,
        "τ beyond any edge: no split"
    );
    let fine = tessellate(&lens, eye, view(eye), TessSettings::new(12.0));
    assert!(fine.stats.added_vertices > 100, "{:?}", fine.stats);
    assert!(fine.indices.len() > 4 * coarse.indices.len());
    assert_eq!(has_t_junction(&fine.positions, &fine.indices), None);
    // Flat splits cover the same surface once, wound like their parents.
    let area = |positions: &[Vec3], indices: &[u32]| -> f32 {
        indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [0, 1, 2].map(|i| positions[t[i] as usize]);
                (b - a).cross(c - a).length() * 0.5
            })
            .sum()
    };
    let (a0, a1) = (
        area(&coarse.positions, &coarse.indices),
        area(&fine.positions, &fine.indices),
    );
    assert!((a0 - a1).abs() < 1e-4 * a0, "{a0} vs {a1}");
    for t in fine.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|i| fine.positions[t[i] as usize]);
        assert!(
            (b - a).cross(c - a).dot(eye - a) > 0.0,
            "front-facing, same winding"
        );
    }
    // Every vertex carries its own paths.
    assert_eq!(fine.paths.len(), fine.positions.len());
}

#[test]
fn tessellation_is_the_same_on_any_number_of_threads() {
    // Masks, children and the re-triangulated leaves run in parallel; the
    // mesh (order included: it is the index buffer) must not depend on it.
    let lens = glass(sphere(Vec3::ZERO, 1.0, 8, 16), 1.5, Vec3::ZERO);
    let eye = Vec3::new(0.5, 1.0, 4.0);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| tessellate(&lens, eye, view(eye), TessSettings::new(6.0)))
    };
    let one = run(1);
    assert!(one.stats.depth >= 2, "{:?}", one.stats);
    for threads in [2, 3] {
        let many = run(threads);
        assert_eq!(many.indices, one.indices, "{threads} threads");
        assert_eq!(many.positions, one.positions, "{threads} threads");
        assert_eq!(many.paths, one.paths, "{threads} threads");
    }
}

#[test]
fn agreeing_paths_are_not_split() {
    // A flat slab far away: every vertex's paths agree within 3°.
    let lens = glass(
        cube(Vec3::new(-0.5, -0.5, -0.05), Vec3::new(0.5, 0.5, 0.05)),
        1.5,
        Vec3::ZERO,
    );
    let eye = Vec3::new(0.0, 0.0, 40.0);
    let t = tessellate(&lens, eye, view(eye), TessSettings::new(0.5));
    assert_eq!(t.stats.added_vertices, 0, "{:?}", t.stats);
    assert_eq!(t.indices.len(), 6, "the front face only");
}

#[test]
fn tau_below_a_subpixel_is_bounded() {
    let lens = glass(sphere(Vec3::ZERO, 1.0, 6, 12), 1.5, Vec3::ZERO);
    let eye = Vec3::new(0.0, 0.5, 3.0);
    let settings = TessSettings {
        max_vertices: 3000,
        ..TessSettings::new(0.01)
    };
    let t = tessellate(&lens, eye, view(eye), settings);
    assert!(t.positions.len() <= 3000, "{}", t.positions.len());
    assert!(t.stats.budget_hit);
    assert_eq!(has_t_junction(&t.positions, &t.indices), None);
    // Without a vertex budget the depth limit still ends it.
    let settings = TessSettings {
        max_depth: 3,
        ..TessSettings::new(0.0)
    };
    let t = tessellate(&lens, eye, view(eye), settings);
    assert!(t.stats.depth <= 3 && !t.stats.budget_hit);
}

#[test]
fn vertex_paths_missing_every_shell_give_finite_lookups() {
    let lens = glass(sphere(Vec3::ZERO, 1.0, 8, 16), 1.5, Vec3::splat(0.3));
    let eye = Vec3::new(0.0, 0.5, 3.0);
    let t = tessellate(&lens, eye, view(eye), TessSettings::new(10.0));
    // Shells the exit rays cannot reach: a sphere far off to the side
    // (the rays start outside it) and a quad behind the eye facing away.
    let shells = ShellSet {
        origin: [50.0, 0.0, 0.0],
        shells: vec![
            Shell {
                shape: ShellShape::Sphere { radius: 1.0 },
                objects: vec![],
                distance: 1.0,
            },
            Shell {
                shape: ShellShape::Quad {
                    center: [0.0, 0.0, 10.0],
                    normal: [0.0, 0.0, 1.0],
                    u: [1.0, 0.0, 0.0],
                    half: [1.0, 1.0],
                },
                objects: vec![],
                distance: 10.0,
            },
        ],
    };
    let mut stream = Vec::new();
    vertex_stream(&t, &shells, &mut stream);
    assert_eq!(stream.len(), t.positions.len() * stride(2));
    assert!(stream.iter().all(|v| v.is_finite()));
}

#[test]
fn screen_refuses_points_behind_the_eye() {
    let s = Screen {
        view_proj: Mat4::IDENTITY,
        width: 10,
        height: 10,
    };
    assert!(s.pixel(Vec3::ZERO).is_some());
    let behind = view(Vec3::new(0.0, 0.0, 3.0));
    assert!(behind.pixel(Vec3::new(0.0, 0.0, 5.0)).is_none());
}

#[test]
fn the_angle_limit_agrees_with_the_angle() {
    use super::path::AngleLimit;
    let mut seed = 3u64;
    let mut next = || {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        (seed >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let (mut over, mut under) = (0, 0);
    for max in [0.5, 3.0, 45.0, 179.0] {
        let limit = AngleLimit::new(max);
        for _ in 0..20_000 {
            let a = Vec3::new(next(), next(), next()).normalize();
            // Mostly near `a`, so angles around the limit are common.
            let spread = next().abs() * max.to_radians() * 2.0;
            let b = (a + spread * Vec3::new(next(), next(), next())).normalize();
            let angle = angle_deg(a, b);
            if (angle - max).abs() < 1e-3 {
                continue;
            }
            assert_eq!(
                limit.exceeded(a, b),
                angle > max,
                "{a} {b}: {angle}° vs {max}°"
            );
            if angle > max { over += 1 } else { under += 1 }
        }
    }
    assert!(over > 1000 && under > 1000, "{over} over, {under} under");
    let nan = Vec3::splat(f32::NAN);
    assert!(AngleLimit::new(3.0).exceeded(nan, Vec3::X));
    assert!(!AngleLimit::new(3.0).exceeded(Vec3::X, Vec3::X));
    assert!(AngleLimit::new(3.0).exceeded(Vec3::X, -Vec3::X));
}
