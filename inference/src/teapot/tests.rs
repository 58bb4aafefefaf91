//! Geometry tests of the tessellated teapot: watertight where it should be, the published
//! extents, unit normals everywhere, the paper's triangle count.

use std::collections::HashMap;

use glam::Vec3;

use super::patch::Patch;
use super::{TeapotPart, Tessellation, tessellate};
use crate::scene::obj::load_obj;

fn teapot(n: u32, part: TeapotPart) -> Tessellation {
    tessellate(n, part).expect("valid segment count")
}

/// Undirected edges (by position group) → directed use counts (forward, backward).
fn edge_uses(t: &Tessellation) -> HashMap<(u32, u32), (u32, u32)> {
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    for tri in t.mesh.indices.chunks_exact(3) {
        let g = [0, 1, 2].map(|k| t.group_of_vertex[tri[k] as usize]);
        for k in 0..3 {
            let (a, b) = (g[k], g[(k + 1) % 3]);
            let e = edges.entry((a.min(b), a.max(b))).or_default();
            if a < b { e.0 += 1 } else { e.1 += 1 }
        }
    }
    edges
}

#[test]
fn triangle_count_matches_the_paper() {
    // 64 n² triangles minus the n collapsed ones at each of the 8 pole patches.
    // (At n = 1 the spout-tip patches' four corners are collinear, so 4 more vanish.)
    assert_eq!(
        teapot(1, TeapotPart::Whole).mesh.triangle_count(),
        64 - 8 - 4
    );
    for n in [2, 7, 25] {
        let t = teapot(n, TeapotPart::Whole);
        assert_eq!(
            t.mesh.triangle_count() as u32,
            64 * n * n - 8 * n,
            "n = {n}"
        );
    }
    assert_eq!(teapot(25, TeapotPart::Whole).mesh.triangle_count(), 39_800);
}

#[test]
fn only_the_genuine_openings_are_open() {
    // Open boundaries, each a ring of 4 patch edges (n segments each) unless noted:
    // body rim (inner edge of patches 0–3), lid rim (outer edge of 24–27), the handle's
    // two ends (2 patch edges each) and the spout's two ends (2 each): 16 n in all.
    // Everything else — between patches, at the poles, body to bottom — is closed.
    for (part, per_segment) in [
        (TeapotPart::Whole, 16),
        (TeapotPart::Body, 12),
        (TeapotPart::Lid, 4),
    ] {
        for n in [3, 25] {
            let t = teapot(n, part);
            let edges = edge_uses(&t);
            let open = edges.values().filter(|(f, b)| f + b == 1).count() as u32;
            assert_eq!(open, per_segment * n, "{part:?}, n = {n}");
            for (e, (f, b)) in &edges {
                assert!(f + b <= 2, "edge {e:?} used {} times", f + b);
                // Consistent orientation: a shared edge is walked once each way.
                assert!(
                    f + b == 1 || (*f == 1 && *b == 1),
                    "edge {e:?} flipped ({f}, {b})"
                );
            }
        }
    }
}

#[test]
fn shared_patch_edges_coincide_from_both_sides() {
    let patches: Vec<Patch> = (0..32).filter_map(Patch::teapot).collect();
    assert_eq!(patches.len(), 32);
    // A boundary as (patch, which, control points); `which` 0..4 = u=0, u=1, v=0, v=1.
    let boundary = |p: &Patch, which: usize| -> [Vec3; 4] {
        std::array::from_fn(|k| match which {
            0 => p.cp[0][k],
            1 => p.cp[3][k],
            2 => p.cp[k][0],
            _ => p.cp[k][3],
        })
    };
    let eval = |p: &Patch, which: usize, t: f32| match which {
        0 => p.eval(0.0, t).position,
        1 => p.eval(1.0, t).position,
        2 => p.eval(t, 0.0).position,
        _ => p.eval(t, 1.0).position,
    };
    let same = |a: [Vec3; 4], b: [Vec3; 4]| a.iter().zip(&b).all(|(x, y)| x.distance(*y) < 1e-6);
    let mut shared = 0;
    for (i, pi) in patches.iter().enumerate() {
        for wi in 0..4 {
            let bi = boundary(pi, wi);
            if bi.iter().all(|p| p.distance(bi[0]) < 1e-6) {
                continue; // collapsed pole edge
            }
            for (j, pj) in patches.iter().enumerate().skip(i + 1) {
                for wj in 0..4 {
                    let bj = boundary(pj, wj);
                    let mut rev = bj;
                    rev.reverse();
                    let reversed = if same(bi, bj) {
                        false
                    } else if same(bi, rev) {
                        true
                    } else {
                        continue;
                    };
                    shared += 1;
                    for s in 0..=50 {
                        let t = s as f32 / 50.0;
                        let a = eval(pi, wi, t);
                        let b = eval(pj, wj, if reversed { 1.0 - t } else { t });
                        assert!(a.distance(b) < 1e-5, "patches {i}/{j} at t={t}: {a} vs {b}");
                    }
                }
            }
        }
    }
    // 32 patches × 4 edges = 128 boundaries; minus 8 collapsed and 16 open ones leaves
    // 104, each shared by two patches.
    assert_eq!(shared, 52);
}

#[test]
fn bounds_match_the_published_extents() {
    // Newell's teapot spans x ∈ [−3.0, 3.434] (handle back to spout tip), y ∈ [−2, 2]
    // and z ∈ [0, 3.15] in its original z-up units (Crow 1987; e.g. Eric Haines' and Steve
    // Baker's notes quote 6.434 × 4 × 3.15). The spout maximum 3.43408 is where the tip
    // curve (3.3, 3.525, 3.45, 3.2) peaks. Here y is up: (x, z, −y).
    let expected_min = Vec3::new(-3.0, 0.0, -2.0);
    let expected_max = Vec3::new(3.434, 3.15, 2.0);
    // Dense evaluation of the patches themselves: the exact surface extents.
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for p in (0..32).filter_map(Patch::teapot) {
        for a in 0..=200 {
            for b in 0..=200 {
                let q = p.eval(a as f32 / 200.0, b as f32 / 200.0).position;
                lo = lo.min(q);
                hi = hi.max(q);
            }
        }
    }
    assert!(lo.abs_diff_eq(expected_min, 1e-3), "{lo}");
    assert!(hi.abs_diff_eq(expected_max, 1e-3), "{hi}");
    // The 25-segment mesh samples the spout tip 0.0002 short of its peak.
    let (mlo, mhi) = teapot(25, TeapotPart::Whole).mesh.bounds();
    assert!(mlo.abs_diff_eq(expected_min, 1e-3), "{mlo}");
    assert!(mhi.abs_diff_eq(expected_max, 1e-3), "{mhi}");
}

#[test]
fn normals_are_unit_outward_and_right_at_the_poles() {
    let t = teapot(25, TeapotPart::Whole);
    let m = &t.mesh;
    assert_eq!(m.normals.len(), m.positions.len());
    for n in &m.normals {
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-5, "{n}");
    }
    let top = Vec3::new(0.0, 3.15, 0.0);
    let pole = |p: Vec3| m.positions.iter().position(|q| q.distance(p) < 1e-5);
    let lid = pole(top).expect("lid pole vertex");
    let bottom = pole(Vec3::ZERO).expect("bottom pole vertex");
    assert!(m.normals[lid].dot(Vec3::Y) > 0.9999, "{}", m.normals[lid]);
    assert!(
        m.normals[bottom].dot(-Vec3::Y) > 0.9999,
        "{}",
        m.normals[bottom]
    );
    // Winding agrees with the normals (front faces outside), and the widest part of
    // the body faces outward.
    for tri in m.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| m.positions[tri[k] as usize]);
        let face = (b - a).cross(c - a);
        let avg: Vec3 = tri.iter().map(|&i| m.normals[i as usize]).sum();
        assert!(
            face.dot(avg) > 0.0,
            "triangle {tri:?} winds against its normals"
        );
    }
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let radial = Vec3::new(p.x, 0.0, p.z);
        if (p.y - 1.1).abs() < 0.2 && radial.length() > 1.95 && p.x.abs() < 1.5 {
            assert!(n.dot(radial.normalize()) > 0.95, "body normal {n} at {p}");
        }
    }
}

#[test]
fn obj_round_trip_through_tobj() {
    let dir = tempfile::tempdir().expect("temp dir");
    let t = teapot(25, TeapotPart::Whole);
    let path = dir.path().join("teapot.obj");
    crate::scene::obj::write_obj(&path, &t.mesh, "round trip").expect("write OBJ");
    let loaded = load_obj(&path).expect("load back");
    assert_eq!(loaded.triangle_count(), t.mesh.triangle_count());
    assert_eq!(loaded.positions.len(), t.mesh.positions.len());
    // tobj may renumber vertices; compare triangles through their corner data.
    for tri in 0..t.mesh.triangle_count() {
        for k in 0..3 {
            let a = t.mesh.indices[3 * tri + k] as usize;
            let b = loaded.indices[3 * tri + k] as usize;
            assert_eq!(t.mesh.positions[a], loaded.positions[b]);
            assert_eq!(t.mesh.normals[a], loaded.normals[b]);
            assert_eq!(t.mesh.uvs[a], loaded.uvs[b]);
        }
    }
}

#[test]
fn bad_segment_counts_are_errors() {
    assert!(tessellate(0, TeapotPart::Whole).is_err());
    assert!(tessellate(super::MAX_SEGMENTS + 1, TeapotPart::Whole).is_err());
}
