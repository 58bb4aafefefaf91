//! Ratio against PSNR on a synthetic PEM, with the JPEG baseline (and the
//! ffmpeg one when available):
//! `cargo run --release -p codec --example curve -- [size] [samples] [ratios...]`
//!
//! `samples` is `N` (a 1D grid) or `N0xN1` (a 2D grid, 8×8 blocks).

use std::time::Instant;

use codec::report::{ReportOptions, report};
use codec::synth::{SynthSpec, scene};
use codec::{Container, EncodeOptions, ParamGrid, Target, encode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size: u32 = args.first().map_or(Ok(64), |s| s.parse())?;
    let grid = match args.get(1).map(|s| s.split_once('x')) {
        None => ParamGrid::one_d(16),
        Some(None) => ParamGrid::one_d(args[1].parse()?),
        Some(Some((a, b))) => ParamGrid::two_d(a.parse()?, b.parse()?),
    };
    let ratios: Vec<f64> = if args.len() > 2 {
        args[2..]
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?
    } else {
        vec![96.0, 192.0, 384.0, 768.0]
    };
    let t0 = Instant::now();
    let input = scene(&SynthSpec::cube(1, 2, grid, size));
    eprintln!(
        "synth {size}x{size}x6, {}x{} samples, 2 layers: {:.2}s",
        grid.n0,
        grid.n1,
        t0.elapsed().as_secs_f64()
    );
    for r in ratios {
        let t = Instant::now();
        let (bytes, enc) = encode(&input, Target::Ratio(r), &EncodeOptions::default())?;
        let enc_s = t.elapsed().as_secs_f64();
        let c = Container::from_bytes(bytes)?;
        let rep = report(&c, &input, &ReportOptions::default())?;
        println!(
            "target {r:>6.0}:1  ratio {:>7.1}  psnr {:>6.2} dB  bytes {:>8}  encode {enc_s:>6.2}s  decode median {:>6.2} ms  plans {:?}",
            rep.ratio,
            rep.psnr_db,
            rep.bytes,
            rep.decode_ms_median,
            enc.textures[0].plans.first()
        );
        for b in &rep.baselines {
            println!(
                "    {:<18} ratio {:>7.1}  psnr {:>6.2} dB  bytes {:>8}  {}",
                b.name,
                b.ratio,
                b.psnr_db,
                b.bytes,
                b.note.clone().unwrap_or_default()
            );
        }
        for n in &rep.notes {
            println!("    note: {n}");
        }
    }
    Ok(())
}
