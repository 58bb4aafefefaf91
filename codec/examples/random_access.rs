//! The pyramid's random access on a container, alone (the full comparison
//! with x264 is `engine codec-report`'s `random_access`):
//! `cargo run --release -p codec --example random_access -- FILE.ptxc [samples]`.

use codec::report::{pyramid_random_access, spread_samples};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = std::path::PathBuf::from(args.next().ok_or("usage: random_access FILE [samples]")?);
    let count: usize = args.next().map_or(Ok(16), |a| a.parse())?;
    let c = codec::Container::open(&path)?;
    let n = c.textures().iter().map(|t| t.grid.len()).max().unwrap_or(0);
    let samples = spread_samples(n, count);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    for threads in [1, cores] {
        let a = pyramid_random_access(&path, &samples, threads)?;
        println!(
            "{:<20} {:>8.2} ms  {:>9} bytes read  (medians over {} samples)",
            a.name, a.ms, a.bytes_read, a.samples
        );
    }
    Ok(())
}
