//! CPU cost per frame of layered glass shells on `glass_near` at 640×480,
//! τ = 10, azimuth 50.5° (the near teapot behind the glass): the vertex
//! stream for the room's one shell, for two layers (laid out for three),
//! and sorting the triangles an inner layer can reach first.
//!
//! `cargo bench -p engine --bench glass_layers`

use criterion::{Criterion, criterion_group, criterion_main};
use engine::glass::coverage::{covered_cone, split_triangles};
use inference::glass::shell_map::{LayerObjects, mip_chain, trace_layer_map};
use inference::glass::vertices::vertex_stream_padded;
use inference::glass::{Lens, MAX_SHELLS, Screen, TessSettings, tessellate};
use inference::scene::Scene;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::load("glass_near").expect("glass_near scene");
    let lens = Lens::new(&scene, "teapot").expect("glass teapot");
    let (w, h) = (640, 480);
    let eye = scene.orbit.eye(50.5, 0.0);
    let screen = Screen {
        view_proj: inference::trace::camera::projection(&scene, w, h) * scene.orbit.view(eye),
        width: w,
        height: h,
    };
    let tess = tessellate(&lens, eye, screen, TessSettings::new(10.0));
    let layered = inference::glass::placement::place_for_scene(&scene, &lens, 2);
    let origin = layered.origin();
    let room =
        inference::glass::room_shell(&scene, origin, inference::glass::room_box_shape(&scene));
    // The inner layer's coverage, from a coarse trace (the cone only).
    let size = 64;
    let tracer = inference::trace::Tracer::new(&scene).expect("tracer");
    let settings = inference::trace::TraceSettings {
        width: size,
        height: 6 * size,
        spp: 1,
        ..Default::default()
    };
    let objects = LayerObjects {
        hidden: &[lens.object],
        own: Some(&layered.shells[0].objects),
    };
    let level0 = trace_layer_map(&tracer, &objects, origin, size, &settings);
    let halves: Vec<half::f16> = mip_chain(level0, size)
        .into_iter()
        .flatten()
        .flat_map(|t| t.map(half::f16::from_f32))
        .collect();
    let cone = covered_cone(bytemuck::cast_slice(&halves), size).expect("the near teapot");
    let mut stream = Vec::new();
    let mut split = Vec::new();
    let mut group = c.benchmark_group(format!("glass_{}_vertices", tess.positions.len()));
    group.bench_function("stream_one_shell", |b| {
        b.iter(|| vertex_stream_padded(black_box(&tess), &room, 1, &mut stream))
    });
    group.bench_function("stream_two_layers", |b| {
        b.iter(|| vertex_stream_padded(black_box(&tess), &layered, MAX_SHELLS, &mut stream))
    });
    group.bench_function("split_triangles", |b| {
        b.iter(|| split_triangles(black_box(&stream), &tess.indices, &[cone], &mut split))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
