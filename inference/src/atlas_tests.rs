//! The atlas gives every surface point its own texels: no texel centre in
//! two triangles, a gutter between charts, one texel density, and the
//! mesh's geometry unchanged.

use super::{Atlas, build};
use crate::scene::Mesh;
use crate::teapot::{TeapotPart, tessellate};
use glam::{Vec2, Vec3};

fn teapot() -> Mesh {
    tessellate(25, TeapotPart::Whole)
        .expect("valid segment count")
        .mesh
}

/// The triangle (index into `tris`) whose interior holds each texel centre
/// of a `resolution`² texture, and how many centres lie in two.
fn rasterize(uvs: &[Vec2], tris: &[u32], resolution: u32) -> (Vec<Option<u32>>, usize) {
    let r = resolution as f32;
    let mut owner = vec![None; (resolution * resolution) as usize];
    let mut twice = 0;
    for (t, tri) in tris.chunks_exact(3).enumerate() {
        let [a, b, c] = [0, 1, 2].map(|k| uvs[tri[k] as usize] * r);
        let lo = a.min(b).min(c).floor().max(Vec2::ZERO);
        let hi = a.max(b).max(c).ceil().min(Vec2::splat(r));
        let area = (b - a).perp_dot(c - a);
        if area.abs() < 1e-12 {
            continue;
        }
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let w = [(b - p).perp_dot(c - p), (c - p).perp_dot(a - p)].map(|w| w / area);
                if w[0] > 1e-6 && w[1] > 1e-6 && 1.0 - w[0] - w[1] > 1e-6 {
                    let cell = &mut owner[(y * resolution + x) as usize];
                    twice += usize::from(cell.is_some());
                    *cell = Some(t as u32);
                }
            }
        }
    }
    (owner, twice)
}

#[test]
fn the_teapots_own_uvs_share_texels_and_its_atlas_does_not() {
    let mesh = teapot();
    let (_, shared) = rasterize(&mesh.uvs, &mesh.indices, 256);
    assert!(
        shared > 1000,
        "cylindrical UVs: {shared} texels in two triangles"
    );
    let atlas = build(&mesh, 256);
    assert!(atlas.charts > 6, "{} charts", atlas.charts);
    assert!(
        atlas
            .uvs
            .iter()
            .all(|uv| uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all())
    );
    let (owner, shared) = rasterize(&atlas.uvs, &atlas.indices, 256);
    assert_eq!(shared, 0, "atlas texels in two triangles");
    let used = owner.iter().filter(|o| o.is_some()).count();
    // Box-projection charts on shelves: 30% of the texels for the teapot
    // (the rings of the lid and shoulders leave their rectangles' middles).
    assert!(
        used > 256 * 256 / 4,
        "the charts fill {used} of 65536 texels"
    );
}

#[test]
fn charts_keep_a_gutter_between_them() {
    let mesh = teapot();
    let atlas = build(&mesh, 256);
    // Charts are the components of triangles sharing atlas vertices.
    let mut parent: Vec<usize> = (0..atlas.uvs.len()).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            v = parent[v];
        }
        v
    }
    for tri in atlas.indices.chunks_exact(3) {
        for k in 1..3 {
            let (a, b) = (
                root(&mut parent, tri[0] as usize),
                root(&mut parent, tri[k] as usize),
            );
            parent[a] = b;
        }
    }
    let chart_of_tri: Vec<usize> = atlas
        .indices
        .chunks_exact(3)
        .map(|tri| root(&mut parent, tri[0] as usize))
        .collect();
    let (owner, _) = rasterize(&atlas.uvs, &atlas.indices, 256);
    let chart = |x: i32, y: i32| {
        (0..256)
            .contains(&x)
            .then_some(())
            .and((0..256).contains(&y).then_some(()))
            .and(owner[(y * 256 + x) as usize])
            .map(|t| chart_of_tri[t as usize])
    };
    let mut touching = 0;
    for y in 0..256 {
        for x in 0..256 {
            let Some(c) = chart(x, y) else { continue };
            for (dx, dy) in [(1, 0), (0, 1), (1, 1), (1, -1), (2, 0), (0, 2)] {
                if chart(x + dx, y + dy).is_some_and(|d| d != c) {
                    touching += 1;
                }
            }
        }
    }
    assert_eq!(touching, 0, "texels of two charts within two texels");
}

#[test]
fn one_texel_density_and_the_geometry_unchanged() {
    let mesh = teapot();
    let atlas = build(&mesh, 256);
    let copy = atlas.mesh(&mesh);
    assert_eq!(copy.triangle_count(), mesh.triangle_count());
    let mut ratios = Vec::new();
    for t in 0..mesh.triangle_count() {
        assert_eq!(copy.triangle(t), mesh.triangle(t));
        let [a, b, c] = mesh.triangle(t);
        let n = (b - a).cross(c - a);
        // The projected area: along the axis the normal faces most.
        let projected = n.abs().max_element();
        let i = &atlas.indices[3 * t..3 * t + 3];
        let [p, q, r] = [0, 1, 2].map(|k| atlas.uvs[i[k] as usize]);
        let uv_area = (q - p).perp_dot(r - p).abs();
        if projected > 1e-4 {
            ratios.push(uv_area / projected);
        }
    }
    let (lo, hi) = ratios
        .iter()
        .fold((f32::MAX, 0.0f32), |(l, h), &r| (l.min(r), h.max(r)));
    assert!(hi / lo < 1.01, "texel density {lo} to {hi}");
}

#[test]
fn charts_that_cannot_fit_keep_the_meshs_own_uvs() {
    // 2,000 separate triangles facing every way cannot fit 8² texels.
    let mut mesh = Mesh::default();
    for k in 0..2000u32 {
        let o = Vec3::new(k as f32 * 3.0, 0.0, 0.0);
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend([o, o + Vec3::X, o + Vec3::Y * (1.0 + (k % 3) as f32)]);
        mesh.normals.extend([Vec3::Z; 3]);
        mesh.uvs.extend([Vec2::ZERO, Vec2::X, Vec2::Y]);
        mesh.indices.extend([base, base + 1, base + 2]);
    }
    let atlas = build(&mesh, 8);
    assert_eq!(atlas.charts, 0);
    assert_eq!(atlas.uvs, mesh.uvs);
    assert_eq!(atlas.mesh(&mesh), mesh);
    assert_ne!(build(&mesh, 4096).charts, 0, "they fit a larger texture");
}

#[test]
fn an_empty_mesh_gives_an_empty_atlas() {
    let atlas = build(&Mesh::default(), 256);
    assert_eq!(
        atlas,
        Atlas {
            source: vec![],
            uvs: vec![],
            indices: vec![],
            charts: 0
        }
    );
}

#[test]
fn small_textures_leave_the_charts_few_texels() {
    // What the engine's smallest PTM edge (64) rests on: the tiny test
    // teapot's charts get a handful of texel centres at 16², hundreds
    // from 64².
    let mesh = tessellate(6, TeapotPart::Whole).expect("valid").mesh;
    let used = |r: u32| {
        let atlas = build(&mesh, r);
        let (owner, shared) = rasterize(&atlas.uvs, &atlas.indices, r);
        assert_eq!(shared, 0, "{r}²");
        owner.iter().filter(|o| o.is_some()).count()
    };
    let (at16, at64) = (used(16), used(64));
    eprintln!("texel centres in the atlas: {at16} at 16², {at64} at 64²");
    assert!(at16 < 32, "{at16} at 16²");
    assert!(at64 > 500, "{at64} at 64²");
}
