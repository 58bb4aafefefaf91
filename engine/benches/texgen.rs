//! CPU texgen per frame on the teapot (PEM paper: 35 ms on a 733 MHz PC):
//! each EM geometry, SIMD per vertex on one core (a version split over
//! both cores with rayon measured no faster here and was dropped).
//!
//! `cargo bench -p engine --bench texgen`

use criterion::{Criterion, criterion_group, criterion_main};
use inference::em_geometry::{EmGeometry, bounding_ellipsoid, texgen};
use inference::scene::Scene;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::load("teapot").expect("teapot scene");
    let teapot = scene.object("teapot").expect("teapot object");
    let (positions, normals) = (&teapot.mesh.positions, &teapot.mesh.normals);
    let origin = teapot.mesh.area_weighted_centroid();
    let (min, max) = scene.bounds();
    let eye = scene.orbit.sample_eye(30).expect("sample");
    let geometries = [
        ("sphere", EmGeometry::SphereAtInfinity),
        ("box", EmGeometry::Box { min, max }),
        (
            "ellipsoid",
            EmGeometry::Ellipsoid {
                center: origin,
                radii: bounding_ellipsoid(origin, positions),
            },
        ),
    ];
    let mut out = vec![[0.0f32; 4]; positions.len()];
    let mut group = c.benchmark_group(format!("texgen_{}_vertices", positions.len()));
    for (name, g) in geometries {
        group.bench_function(name, |b| {
            b.iter(|| texgen(&g, origin, black_box(eye), positions, normals, &mut out))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
