//! Which teapot triangles lie on its convex hull, and how long that takes:
//! `cargo run --release -p inference --example hull_bench -- [RUNS] [--check]`
//! (median of RUNS timed runs, default 5; `--check` compares with the
//! brute-force O(triangles × vertices) test).

use inference::hull::{RELATIVE_TOLERANCE, hull_triangles};
use inference::scene::Scene;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let runs: usize = match args.iter().find(|a| !a.starts_with("--")) {
        Some(r) => r.parse().map_err(|e| format!("RUNS {r:?}: {e}"))?,
        None => 5,
    };
    let check = args.iter().any(|a| a == "--check");
    let scene = Scene::load("teapot")?;
    let mesh = &scene
        .object("teapot")
        .ok_or("the teapot scene has no object \"teapot\"")?
        .mesh;
    let mut times = Vec::new();
    let mut flags = Vec::new();
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        flags = hull_triangles(mesh);
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let on = flags.iter().filter(|&&f| f).count();
    println!(
        "teapot: {} triangles, {} vertices; {on} on the hull ({:.1}%); median {:.1} ms over {} runs (min {:.1}, max {:.1}) on {} threads",
        flags.len(),
        mesh.positions.len(),
        100.0 * on as f64 / flags.len().max(1) as f64,
        1e3 * times[times.len() / 2],
        times.len(),
        1e3 * times[0],
        1e3 * times[times.len() - 1],
        rayon::current_num_threads()
    );
    if check {
        let start = Instant::now();
        let (lo, hi) = mesh.bounds();
        let max_abs = lo.abs().max(hi.abs()).max_element() as f64;
        let tol = RELATIVE_TOLERANCE * (hi - lo).as_dvec3().length()
            + 8.0 * f64::from(f32::EPSILON) * max_abs;
        let points: Vec<_> = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
        let mut differ = 0;
        for (t, &f) in flags.iter().enumerate() {
            let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
            let n = (b - a).cross(c - a).normalize();
            let d = n.dot(a) + tol;
            let brute = points.iter().all(|p| n.dot(*p) <= d);
            differ += usize::from(brute != f);
        }
        println!(
            "brute force: {differ} triangles differ ({:.1} s)",
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
