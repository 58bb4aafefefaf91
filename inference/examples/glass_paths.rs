//! Per-frame CPU cost of hybrid glass: adaptive tessellation with vertex
//! ray paths of the glass scene's teapot at one view, for several τ.
//! `cargo run --release -p inference --example glass_paths -- [repeats] [scene]`

use std::time::Instant;

use inference::glass::{Lens, Screen, TessSettings, tessellate};
use inference::scene::Scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: usize = std::env::args().nth(1).map_or(Ok(5), |s| s.parse())?;
    let name = std::env::args().nth(2).unwrap_or_else(|| "glass".into());
    let scene = Scene::load(&name)?;
    let lens = Lens::new(&scene, "teapot")?;
    let eye = scene.orbit.eye(30.5, 0.0);
    let (width, height) = (640, 480);
    let view_proj =
        inference::trace::camera::projection(&scene, width, height) * scene.orbit.view(eye);
    let screen = Screen {
        view_proj,
        width,
        height,
    };
    println!(
        "base mesh: {} vertices, {} triangles",
        lens.mesh.positions.len(),
        lens.triangle_count()
    );
    // Raw ray cost: from the centroid outwards, one thread.
    let c = lens.mesh.area_weighted_centroid();
    let n = 200_000;
    let start = Instant::now();
    let mut hits = 0;
    for i in 0..n {
        let a = i as f32 * 0.618_034 * std::f32::consts::TAU;
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let r = (1.0 - z * z).sqrt();
        let d = glam::Vec3::new(r * a.cos(), z, r * a.sin());
        hits += usize::from(lens.closest(c, d).is_some());
    }
    println!(
        "raw: {:.3} µs per ray from the centroid, one thread ({hits} hits)",
        start.elapsed().as_secs_f64() * 1e6 / n as f64
    );
    for tau in [3.0, 5.0, 10.0, 30.0, 1e6] {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..repeats {
            let start = Instant::now();
            let t = tessellate(&lens, eye, screen, TessSettings::new(tau));
            times.push(start.elapsed().as_secs_f64() * 1e3);
            last = Some(t);
        }
        times.sort_by(f64::total_cmp);
        let t = last.ok_or("no repeats")?;
        // The same vertices' paths alone, in parallel: what tracing costs.
        let start = Instant::now();
        let traced: Vec<_> = {
            use rayon::prelude::*;
            t.positions
                .par_iter()
                .zip(&t.normals)
                .zip(&t.on)
                .map(|((p, n), on)| {
                    inference::glass::path::vertex_paths(&lens, eye, (*p, *n), Some(*on))
                })
                .collect()
        };
        let paths_ms = start.elapsed().as_secs_f64() * 1e3;
        assert_eq!(traced.len(), t.positions.len());
        println!("tau {tau:>7}: paths alone {paths_ms:.1} ms");
        println!(
            "tau {tau:>7}: {:>7} vertices ({} base, {} added), {:>7} triangles, {:>8} rays, depth {}, {:.1} ms median",
            t.positions.len(),
            t.stats.base_vertices,
            t.stats.added_vertices,
            t.indices.len() / 3,
            t.stats.rays,
            t.stats.depth,
            times[times.len() / 2]
        );
    }
    Ok(())
}
