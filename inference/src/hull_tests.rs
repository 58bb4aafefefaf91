//! Tests of the convex-hull flags (a child module of `hull.rs`).

use super::*;
use glam::{Vec2, Vec3};

fn mesh(positions: Vec<Vec3>, indices: Vec<u32>) -> Mesh {
    let n = positions.len();
    Mesh {
        positions,
        normals: vec![Vec3::Y; n],
        uvs: vec![Vec2::ZERO; n],
        indices,
    }
}

/// Axis-aligned box `lo..hi`, each face an `s × s` grid of quads, wound
/// counter-clockwise seen from outside.
fn grid_box(lo: Vec3, hi: Vec3, s: u32) -> Mesh {
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for axis in 0..3 {
        for side in [0.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u32;
            for i in 0..=s {
                for j in 0..=s {
                    let mut t = Vec3::ZERO;
                    t[axis] = side;
                    t[u] = i as f32 / s as f32;
                    t[v] = j as f32 / s as f32;
                    positions.push(lo + (hi - lo) * t);
                }
            }
            for i in 0..s {
                for j in 0..s {
                    let a = base + i * (s + 1) + j;
                    let (b, c, d) = (a + s + 1, a + 1, a + s + 2);
                    // (u × v) = +axis: CCW from outside on the max side.
                    if side == 1.0 {
                        indices.extend([a, b, d, a, d, c]);
                    } else {
                        indices.extend([a, d, b, a, c, d]);
                    }
                }
            }
        }
    }
    mesh(positions, indices)
}

fn brute_force(m: &Mesh, relative: f64) -> Vec<bool> {
    let used: Vec<[f64; 3]> = m
        .indices
        .iter()
        .filter_map(|&i| m.positions.get(i as usize))
        .filter(|p| p.is_finite())
        .map(|p| p.as_dvec3().to_array())
        .collect();
    let tol = Tree::new(used.clone()).tolerance(relative);
    (0..m.triangle_count())
        .map(|t| {
            let [a, b, c] = m.triangle(t);
            if is_degenerate([a, b, c]) {
                return false;
            }
            let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
            let n = (b - a).cross(c - a).normalize();
            let d = n.dot(a) + tol;
            used.iter().all(|&p| dot(n.to_array(), p) <= d)
        })
        .collect()
}

#[test]
fn every_face_of_a_box_is_on_the_hull_even_finely_split_and_far_away() {
    for (lo, hi, s) in [
        (Vec3::ZERO, Vec3::ONE, 1),
        (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(3.0, 0.5, 2.0), 7),
        // Far from the origin: f32 coordinates are coarse there.
        (Vec3::splat(1000.0), Vec3::splat(1000.3), 5),
    ] {
        let m = grid_box(lo, hi, s);
        let flags = hull_triangles(&m);
        assert_eq!(flags.len(), m.triangle_count());
        assert!(flags.iter().all(|&f| f), "{lo} {hi} {s}: {flags:?}");
    }
}

#[test]
fn a_face_that_sees_a_touching_part_leaves_the_hull_among_it() {
    // Box a = [0,1]³ and box b = [1,2]×[0,1]², touching along x = 1.
    let a = grid_box(Vec3::ZERO, Vec3::ONE, 2);
    let b = grid_box(Vec3::X, Vec3::new(2.0, 1.0, 1.0), 2);
    let alone = hull_triangles(&a);
    let among = hull_triangles_among(&a, &[&b]);
    assert!(alone.iter().all(|&f| f));
    assert_eq!(among.len(), a.triangle_count());
    for (t, &on) in among.iter().enumerate() {
        let [p, q, r] = a.triangle(t);
        let facing_b = [p, q, r].iter().all(|v| v.x == 1.0);
        // Only a's +x face sees b; its other faces stay on the hull.
        assert_eq!(on, !facing_b, "triangle {t}: {p} {q} {r}");
    }
    // Nothing else changes: among no others is the mesh's own hull.
    assert_eq!(hull_triangles_among(&a, &[]), alone);
}

#[test]
fn the_dimple_of_a_concave_box_is_not_on_the_hull() {
    // A unit cube whose top face is a four-sided pyramid pushed inward.
    let mut m = grid_box(Vec3::ZERO, Vec3::ONE, 1);
    // The +y face is the one with axis 1, side 1: triangles 6 and 7.
    let keep: Vec<u32> = m
        .indices
        .chunks_exact(3)
        .enumerate()
        .filter(|(t, _)| *t != 6 && *t != 7)
        .flat_map(|(_, c)| c.to_vec())
        .collect();
    m.indices = keep;
    let corner = |x: f32, z: f32| {
        m.positions
            .iter()
            .position(|p| *p == Vec3::new(x, 1.0, z))
            .expect("corner") as u32
    };
    let (a, b, c, d) = (
        corner(0.0, 0.0),
        corner(1.0, 0.0),
        corner(1.0, 1.0),
        corner(0.0, 1.0),
    );
    let apex = m.positions.len() as u32;
    m.positions.push(Vec3::new(0.5, 0.6, 0.5));
    m.normals.push(Vec3::Y);
    m.uvs.push(Vec2::ZERO);
    // Each wound to face up and out of the dimple.
    m.indices
        .extend([a, apex, b, b, apex, c, c, apex, d, d, apex, a]);
    let flags = hull_triangles(&m);
    assert_eq!(flags.len(), 14);
    assert!(flags[..10].iter().all(|&f| f), "{flags:?}");
    assert!(flags[10..].iter().all(|&f| !f), "{flags:?}");
    assert_eq!(flags, brute_force(&m, RELATIVE_TOLERANCE));
    // An inward-wound hull face is conservatively off the hull.
    m.indices.swap(0, 1);
    assert!(!hull_triangles(&m)[0]);
}

#[test]
fn degenerate_and_broken_triangles_are_off_the_hull_without_panicking() {
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        2.0 * Vec3::X,
        Vec3::new(f32::NAN, 0.0, 0.0),
        Vec3::splat(f32::INFINITY),
    ];
    let m = mesh(
        p,
        vec![
            0, 2, 1, // three hull faces of the tetrahedron 0, X, Y, Z
            0, 1, 3, //
            0, 3, 2, //
            1, 2, 3, // its fourth face, off the hull because of 2X
            0, 1, 1, // repeated corner
            0, 1, 4, // collinear
            0, 1, 5, // NaN corner
            0, 6, 1, // infinite corner
            0, 1, 99, // index out of range
            0, 1, // a trailing partial triangle is not a triangle
        ],
    );
    assert_eq!(
        hull_triangles(&m),
        [true, true, true, false, false, false, false, false, false]
    );
    assert!(hull_triangles(&Mesh::default()).is_empty());
    // A single flat triangle is its own hull; a tiny one too.
    let tiny = mesh(
        vec![Vec3::ZERO, Vec3::X * 1e-6, Vec3::Y * 1e-6],
        vec![0, 1, 2],
    );
    assert_eq!(hull_triangles(&tiny), [true]);
    // Negative or NaN tolerances count as zero.
    let cube = grid_box(Vec3::ZERO, Vec3::ONE, 3);
    for tol in [-1.0, f64::NAN] {
        assert!(hull_triangles_with_tolerance(&cube, tol).iter().all(|&f| f));
    }
}

proptest::proptest! {
    #[test]
    fn the_tree_agrees_with_brute_force(
        coords in proptest::collection::vec(-1.0f32..1.0, 3 * 200),
        tris in proptest::collection::vec(0u32..200, 3 * 150),
    ) {
        let positions = coords
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let m = mesh(positions, tris);
        proptest::prop_assert_eq!(hull_triangles(&m), brute_force(&m, RELATIVE_TOLERANCE));
    }
}

#[test]
fn teapot_hull_leaves_out_the_inside_of_the_handle_and_spout() {
    let scene = crate::scene::Scene::load("teapot").expect("teapot scene");
    let teapot = scene.object("teapot").expect("teapot object");
    let m = &teapot.mesh;
    let flags = hull_triangles(m);
    assert_eq!(flags.len(), m.triangle_count());
    let on = flags.iter().filter(|&&f| f).count();
    let fraction = on as f64 / flags.len() as f64;
    eprintln!(
        "teapot: {on} of {} triangles on the hull ({:.1}%)",
        flags.len(),
        100.0 * fraction
    );
    // The scene scales the model (body radius 2, handle back at x = −3,
    // spout tip at x = 3.43 in model units) by 0.16, centred on x = 0.
    let (lo, hi) = m.bounds();
    let scale = (hi.x - lo.x) / 6.434;
    let body_radius = 2.0 * scale;
    let (mut handle_inner, mut spout_inner) = (0, 0);
    for (t, &f) in flags.iter().enumerate() {
        let [a, b, c] = m.triangle(t);
        let centre = (a + b + c) / 3.0;
        let normal = (b - a).cross(c - a).normalize_or_zero();
        // Handle faces facing the body, beyond its widest radius.
        if centre.x < -1.05 * body_radius && normal.x > 0.3 {
            handle_inner += 1;
            assert!(!f, "handle interior face {t} at {centre} is on the hull");
        }
        // Spout faces facing back towards the body.
        if centre.x > 1.05 * body_radius && normal.x < -0.3 {
            spout_inner += 1;
            assert!(!f, "spout interior face {t} at {centre} is on the hull");
        }
    }
    assert!(
        handle_inner > 100 && spout_inner > 100,
        "{handle_inner} {spout_inner}"
    );
    // The widest part of the body, away from spout and handle, and the
    // top of the lid knob are on the hull.
    let mut widest = 0;
    for (t, &f) in flags.iter().enumerate() {
        let [a, b, c] = m.triangle(t);
        let centre = (a + b + c) / 3.0;
        if centre.z.abs() > 0.98 * body_radius {
            widest += 1;
            assert!(f, "widest body face {t} at {centre} is off the hull");
        }
    }
    assert!(widest > 10, "{widest}");
    let top = flags
        .iter()
        .enumerate()
        .filter(|&(t, _)| m.triangle(t).iter().all(|p| p.y > hi.y - 0.01 * scale))
        .collect::<Vec<_>>();
    assert!(!top.is_empty() && top.iter().all(|(_, f)| **f));
    // The bottom, a shallow convex bowl (rising 0.05 model units from the
    // pole over most of its radius), is on the hull.
    let bottom: Vec<bool> = (0..flags.len())
        .filter(|&t| m.triangle(t).iter().all(|p| p.y <= lo.y + 0.05 * scale))
        .map(|t| flags[t])
        .collect();
    assert!(
        bottom.len() > 1000 && bottom.iter().all(|&f| f),
        "{}",
        bottom.len()
    );
    // Measured 23.0% (9,139 of 39,800): handle, spout, most of the lid
    // and the body behind handle and spout lie under the hull.
    assert!((0.2..0.26).contains(&fraction), "{fraction}");
}
