//! How alike neighbouring parameter samples of the real PEM are: PSNR of
//! each sample against the next, of the linear interpolation of a sample
//! from its two neighbours, and the gain of block motion compensation
//! (16×16 blocks, ±6 texels, integer, on √G of MIP 0) over none.
//!
//! `cargo run --release -p codec --example pem_stats -- [DIR] [SAMPLES]`

#[path = "pem/load.rs"]
mod load;

use codec::{ParamTexture, psnr};

const B: usize = 16;
const R: i64 = 6;

/// (zero-motion, best-motion) squared error of predicting `b` from `a`.
fn motion_sse(t: &ParamTexture, a: &[f32], b: &[f32]) -> (f64, f64) {
    let ch = t.layout.channels as usize;
    let (w, h) = t.layout.mip_size(0);
    let q = |v: f32| (v.signum() * v.abs().sqrt()) as f64;
    let (mut zero, mut best) = (0.0, 0.0);
    for f in 0..t.layout.faces {
        let o = t.layout.texel_offset(f, 0) * ch;
        let px = |img: &[f32], x: i64, y: i64| {
            let x = x.clamp(0, w as i64 - 1) as usize;
            let y = y.clamp(0, h as i64 - 1) as usize;
            q(img[o + (y * w + x) * ch + 1])
        };
        for by in (0..h).step_by(B) {
            for bx in (0..w).step_by(B) {
                let mut b_best = f64::INFINITY;
                for dy in -R..=R {
                    for dx in -R..=R {
                        let mut sse = 0.0;
                        for y in by..(by + B).min(h) {
                            for x in bx..(bx + B).min(w) {
                                let (x, y) = (x as i64, y as i64);
                                let d = px(b, x, y) - px(a, x + dx, y + dy);
                                sse += d * d;
                            }
                        }
                        if dx == 0 && dy == 0 {
                            zero += sse;
                        }
                        b_best = b_best.min(sse);
                    }
                }
                best += b_best;
            }
        }
    }
    (zero, best)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = args
        .first()
        .map_or("/work/data/teapot/infer", |s| s.as_str());
    let n: u32 = args.get(1).map_or(Ok(8), |s| s.parse())?;
    let input = load::load(dir.as_ref(), "teapot", 256, n, &[0, 1, 2])?;
    for (t, (name, _, _)) in input.textures.iter().zip(load::LAYERS) {
        let ch = t.layout.channels as usize;
        let (mut nb, mut interp, mut zero, mut best) = (Vec::new(), Vec::new(), 0.0, 0.0);
        for s in 0..n as usize - 1 {
            nb.push(psnr(t.sample(s + 1), ch, t.sample(s), ch));
            if s + 2 < n as usize {
                let mid: Vec<f32> = t
                    .sample(s)
                    .iter()
                    .zip(t.sample(s + 2))
                    .map(|(a, b)| 0.5 * (a + b))
                    .collect();
                interp.push(psnr(t.sample(s + 1), ch, &mid, ch));
            }
            let (z, b) = motion_sse(t, t.sample(s), t.sample(s + 1));
            zero += z;
            best += b;
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        println!(
            "{name}: next sample {:.1} dB, interpolated from both neighbours {:.1} dB, block motion gain {:.2} dB",
            mean(&nb),
            mean(&interp),
            10.0 * (zero / best).log10()
        );
    }
    Ok(())
}
