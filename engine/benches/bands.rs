//! CPU cost per frame of the compositing pass's scissor bands
//! (`engine::passes::bands::screen_bands`) and of the edge filter's
//! outline tiles (`engine::passes::outline`) on the teapot at 640×480.
//!
//! `cargo bench -p engine --bench bands`

use criterion::{Criterion, criterion_group, criterion_main};
use engine::passes::bands::screen_bands;
use engine::passes::outline::MeshEdges;
use inference::scene::Scene;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::load("teapot").expect("teapot scene");
    let teapot = scene.object("teapot").expect("teapot object");
    let (positions, indices) = (&teapot.mesh.positions, &teapot.mesh.indices);
    let (w, h) = (640, 480);
    let eye = scene.orbit.sample_eye(30).expect("sample");
    let view_proj = inference::trace::camera::projection(&scene, w, h) * scene.orbit.view(eye);
    let mut pixels = Vec::new();
    let mut group = c.benchmark_group(format!("bands_{}_triangles", indices.len() / 3));
    group.bench_function("screen_bands", |b| {
        b.iter(|| {
            screen_bands(
                black_box(view_proj),
                positions,
                indices,
                (w, h),
                &mut pixels,
            )
        })
    });
    let edges = MeshEdges::new(positions, indices);
    screen_bands(view_proj, positions, indices, (w, h), &mut pixels).expect("in view");
    group.bench_function("outline_tiles", |b| {
        b.iter(|| edges.outline_tiles(black_box(&pixels), indices, (w, h)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
