//! Times the teapot's mesh pipeline: tessellate (what `Scene::load` does for a generated
//! mesh), write OBJ → load via tobj (what a user's OBJ costs), and a full `Scene::load` of
//! the teapot scene (textures baked).
//!
//! `cargo run --release -p inference --example teapot_obj -- [segments] [runs]`

use std::error::Error;
use std::time::Instant;

use inference::scene::Scene;
use inference::scene::obj::{load_obj, write_obj};
use inference::teapot::{DEFAULT_SEGMENTS, TeapotPart, tessellate};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let segments: u32 = args
        .next()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(DEFAULT_SEGMENTS);
    let runs: usize = args
        .next()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(5)
        .max(1);
    let dir = std::env::temp_dir().join(format!("teapot_obj_bench_{}", std::process::id()));
    let path = dir.join("teapot.obj");

    let (mut tess, mut write, mut load, mut scene) = (vec![], vec![], vec![], vec![]);
    let mut triangles = 0;
    for _ in 0..runs {
        let t0 = Instant::now();
        let t = tessellate(segments, TeapotPart::Whole)?;
        let t1 = Instant::now();
        write_obj(&path, &t.mesh, "benchmark")?;
        let t2 = Instant::now();
        let m = load_obj(&path)?;
        let t3 = Instant::now();
        triangles = m.triangle_count();
        tess.push((t1 - t0).as_secs_f64() * 1e3);
        write.push((t2 - t1).as_secs_f64() * 1e3);
        load.push((t3 - t2).as_secs_f64() * 1e3);

        let t4 = Instant::now();
        Scene::load("teapot")?;
        scene.push(t4.elapsed().as_secs_f64() * 1e3);
    }
    let size = std::fs::metadata(&path)?.len();
    std::fs::remove_dir_all(&dir)?;
    println!(
        "segments {segments}: {triangles} triangles, OBJ {:.1} MB, median of {runs} runs:",
        size as f64 / 1e6
    );
    println!("  tessellate+weld {:7.1} ms", median(tess.clone()));
    println!("  write OBJ       {:7.1} ms", median(write.clone()));
    println!("  load OBJ (tobj) {:7.1} ms", median(load.clone()));
    println!(
        "  total           {:7.1} ms",
        median(
            tess.iter()
                .zip(&write)
                .zip(&load)
                .map(|((a, b), c)| a + b + c)
                .collect()
        )
    );
    println!(
        "  Scene::load(\"teapot\"):           {:7.1} ms",
        median(scene)
    );
    Ok(())
}
