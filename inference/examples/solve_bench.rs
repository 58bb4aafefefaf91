//! Times the least-squares texture solve on a synthetic problem shaped like
//! the real one: a mirrored sphere filling ~100k pixels of a 640×480 view,
//! each visible pixel a trilinear cube-map lookup (≤ 8 weights) into a
//! 256×256×6 cube map with its full MIP chain (~524k texels). Reports the
//! median over runs of setup and per-channel solve time and CG iterations to
//! relative residual 1e-4, for the A and AᵀA forms, on 1 and 2 rayon threads
//! ("warm" = started from the previous sample's solution, b changed ~1%).
//!
//! `cargo run --release -p inference --example solve_bench -- [runs] [size]`

use std::error::Error;
use std::time::Instant;

use inference::solve::seams::cube_face_uv;
use inference::solve::{
    CsrBuilder, CsrMatrix, Form, SolveError, SolveOptions, Solver, TextureLayout, TextureShape,
    solve_channels,
};

/// User + system CPU seconds of the whole process (all threads), from
/// /proc/self/stat; the machine is shared, so this is steadier than wall time.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are 14, 15.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .filter_map(|t| t.parse().ok())
        .collect();
    // rest starts at field 3 (state, not numeric, is skipped by the parse).
    match (f.get(10), f.get(11)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Reflection of the view ray off a unit sphere seen orthographically.
fn reflect_dir(px: f64, py: f64, cx: f64, cy: f64, r: f64) -> Option<[f64; 3]> {
    let (nx, ny) = ((px - cx) / r, (py - cy) / r);
    let nz2 = 1.0 - nx * nx - ny * ny;
    if nz2 <= 0.0 {
        return None;
    }
    let n = [nx, ny, nz2.sqrt()];
    let d = [0.0, 0.0, -1.0];
    let dn = d[2] * n[2];
    Some([
        d[0] - 2.0 * dn * n[0],
        d[1] - 2.0 * dn * n[1],
        d[2] - 2.0 * dn * n[2],
    ])
}

fn build_problem(
    layout: &TextureLayout,
    size: u32,
) -> Result<(CsrMatrix, Vec<f32>), Box<dyn Error>> {
    let (w, h) = (640.0, 480.0);
    let r = (100_000.0 / std::f64::consts::PI).sqrt(); // ~100k visible pixels
    let (cx, cy) = (w / 2.0, h / 2.0);
    let mut bld = CsrBuilder::new(layout.len());
    let mut row = Vec::with_capacity(8);
    let last = layout.levels() - 1;
    for py in 0..480 {
        for px in 0..640 {
            let (fx, fy) = (px as f64 + 0.5, py as f64 + 0.5);
            let (Some(d), Some(dx), Some(dy)) = (
                reflect_dir(fx, fy, cx, cy, r),
                reflect_dir(fx + 1.0, fy, cx, cy, r),
                reflect_dir(fx, fy + 1.0, cx, cy, r),
            ) else {
                continue;
            };
            let (face, u, v) = cube_face_uv(d);
            // LOD from the footprint of one pixel (approximate at face seams).
            let (_, ux, vx) = cube_face_uv(dx);
            let (_, uy, vy) = cube_face_uv(dy);
            let fp = ((ux - u).hypot(vx - v)).max((uy - u).hypot(vy - v)) * size as f64;
            let lod = fp.max(1e-9).log2().clamp(0.0, last as f64);
            let l0 = (lod.floor() as u32).min(last);
            let l1 = (l0 + 1).min(last);
            let t = (lod - l0 as f64) as f32;
            row.clear();
            for (level, wl) in [(l0, 1.0 - t), (l1, t)] {
                let (lw, lh) = layout.level_size(level);
                let (su, sv) = (u * lw as f64 - 0.5, v * lh as f64 - 0.5);
                let (x0, y0) = (su.floor(), sv.floor());
                let (ax, ay) = ((su - x0) as f32, (sv - y0) as f32);
                let cl = |c: f64, n: u32| c.clamp(0.0, (n - 1) as f64) as u32;
                for (yy, wy) in [(y0, 1.0 - ay), (y0 + 1.0, ay)] {
                    for (xx, wx) in [(x0, 1.0 - ax), (x0 + 1.0, ax)] {
                        let i = layout.index(face, level, cl(xx, lw), cl(yy, lh));
                        row.push((i as u32, wl * wy * wx));
                    }
                }
            }
            bld.push_row(&row)?;
        }
    }
    let a = bld.finish();
    // Ground truth: a smooth pattern with some detail, rendered through A.
    let x_true: Vec<f32> = (0..layout.len())
        .map(|i| {
            let (f, _, x, y) = layout.coords(i);
            0.5 + 0.3 * ((x as f32 * 0.11 + f as f32).sin() * (y as f32 * 0.07).cos())
        })
        .collect();
    let mut b = vec![0.0f32; a.rows];
    a.mul(&x_true, &mut b);
    // ±2% deterministic "tracer vs rasterizer" mismatch: b is not exactly
    // in the range of A, like real data.
    for (i, v) in b.iter_mut().enumerate() {
        let h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
        *v *= 1.0 + 0.04 * (h as f32 / (1u64 << 24) as f32 - 0.5);
    }
    Ok((a, b))
}

struct Run {
    setup: f64,
    wall: f64,
    cpu: f64,
    iterations: f64,
    residual: f64,
}

fn run_once(
    a: &CsrMatrix,
    layout: &TextureLayout,
    options: &SolveOptions,
    b: &[f32],
    x0: Option<&[f32]>,
) -> Result<(Run, Vec<f32>), SolveError> {
    let t0 = Instant::now();
    let solver = Solver::new(a, layout, options)?;
    let (t1, c1) = (Instant::now(), cpu_seconds());
    let s = solver.solve(b, x0)?;
    let (t2, c2) = (Instant::now(), cpu_seconds());
    if !s.converged {
        println!("  not converged: {:?}", s.diagnostic);
    }
    let run = Run {
        setup: (t1 - t0).as_secs_f64(),
        wall: (t2 - t1).as_secs_f64(),
        cpu: c2 - c1,
        iterations: s.iterations as f64,
        residual: s.relative_residual as f64,
    };
    Ok((run, s.x))
}

/// The benchmark's system: A, its layout, b, and the neighbouring
/// parameter sample's b (the same A, b off by ~1%).
struct Problem<'a> {
    a: &'a CsrMatrix,
    layout: &'a TextureLayout,
    b: &'a [f32],
    b_next: &'a [f32],
}

/// The single-channel cases: name, form, eps_b, warm-started.
const CASES: [(&str, Form, f32, bool); 5] = [
    ("A", Form::A, 0.0, false),
    ("NormalMatrix", Form::NormalMatrix, 0.0, false),
    ("A warm", Form::A, 0.0, true),
    ("NormalMatrix warm", Form::NormalMatrix, 0.0, true),
    ("A eps_b=1/32", Form::A, 1.0 / 32.0, false),
];

/// Prints the problem's size and AᵀA's fill, and which form the K-switch picks.
fn describe_problem(
    a: &CsrMatrix,
    layout: &TextureLayout,
    built_since: Instant,
) -> Result<(), Box<dyn Error>> {
    println!(
        "problem: n_s = {} rows, n_t = {} texels, nnz = {} ({:.2}/row), built in {:.2} s",
        a.rows,
        a.cols,
        a.nnz(),
        a.nnz() as f64 / a.rows as f64,
        built_since.elapsed().as_secs_f64()
    );
    let ata = a.normal_matrix();
    println!(
        "AᵀA: nnz = {} ({:.2} per texel, {:.2}× nnz(A)); K-switch picks {:?}",
        ata.nnz(),
        ata.nnz() as f64 / a.cols as f64,
        ata.nnz() as f64 / a.nnz() as f64,
        Solver::new(a, layout, &SolveOptions::default())?.form()
    );
    Ok(())
}

/// One row of the table: the medians of `runs` solves of one case.
fn time_case(
    pool: &rayon::ThreadPool,
    threads: usize,
    p: &Problem,
    (name, form, eps_b, warm): (&str, Form, f32, bool),
    runs: usize,
) -> Result<(), Box<dyn Error>> {
    let options = SolveOptions {
        force_form: Some(form),
        eps_b,
        tolerance: 1e-4,
        max_iterations: 5000,
        ..SolveOptions::default()
    };
    let mut rs = Vec::new();
    for _ in 0..runs {
        let r = pool.install(|| -> Result<Run, SolveError> {
            if warm {
                let (_, x_prev) = run_once(p.a, p.layout, &options, p.b, None)?;
                Ok(run_once(p.a, p.layout, &options, p.b_next, Some(&x_prev))?.0)
            } else {
                Ok(run_once(p.a, p.layout, &options, p.b, None)?.0)
            }
        })?;
        rs.push(r);
    }
    let m = |f: fn(&Run) -> f64| median(rs.iter().map(f).collect());
    println!(
        "{threads:>7} {name:<18} {:>8.3} {:>8.3} {:>12.2} {:>11} {:>13.2e}",
        m(|r| r.setup),
        m(|r| r.wall),
        m(|r| r.cpu),
        m(|r| r.iterations),
        m(|r| r.residual)
    );
    Ok(())
}

/// RGB: three channels of one A through solve_channels (setup shared,
/// channels in parallel); times are per channel.
fn time_rgb(
    pool: &rayon::ThreadPool,
    threads: usize,
    p: &Problem,
    runs: usize,
) -> Result<(), Box<dyn Error>> {
    let options = SolveOptions {
        tolerance: 1e-4,
        max_iterations: 5000,
        ..SolveOptions::default()
    };
    let greens: Vec<f32> = p.b.iter().map(|v| 0.8 * v).collect();
    let bs: Vec<&[f32]> = vec![p.b, p.b_next, &greens];
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let (t0, c0) = (Instant::now(), cpu_seconds());
        let sols = pool.install(|| solve_channels(p.a, &bs, p.layout, None, &options))?;
        wall.push(t0.elapsed().as_secs_f64() / 3.0);
        cpu.push((cpu_seconds() - c0) / 3.0);
        if sols.iter().any(|s| !s.converged) {
            println!("  a channel did not converge");
        }
    }
    println!(
        "{threads:>7} {:<18} {:>8} {:>8.3} {:>12.2}   (per channel, setup included)",
        "RGB solve_channels",
        "-",
        median(wall),
        median(cpu)
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let runs: usize = args
        .next()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(5)
        .max(1);
    let size: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(256);
    let layout = TextureLayout::full_chain(TextureShape::Cube { size });
    let t = Instant::now();
    let (a, b) = build_problem(&layout, size)?;
    describe_problem(&a, &layout, t)?;
    // The neighbouring parameter sample: the same A, b off by ~1%.
    let b_next: Vec<f32> = b
        .iter()
        .enumerate()
        .map(|(i, v)| v * (1.0 + 0.01 * ((i as f32) * 0.01).sin()))
        .collect();
    println!("runs = {runs}; medians; tolerance 1e-4, eps_f = 0.1");
    println!("threads case               setup_s  solve_s  solve_cpu_s  iterations  rel_residual");
    let problem = Problem {
        a: &a,
        layout: &layout,
        b: &b,
        b_next: &b_next,
    };
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        for case in CASES {
            time_case(&pool, threads, &problem, case, runs)?;
        }
        time_rgb(&pool, threads, &problem, runs)?;
    }
    Ok(())
}
