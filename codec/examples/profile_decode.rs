//! Decodes one leaf EM (256×256×6 + MIPs) many times, for profilers.
use codec::synth::{SynthSpec, scene};
use codec::{Container, DecodeCache, EncodeOptions, Lifetimes, ParamGrid, Target, encode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let input = scene(&SynthSpec::cube(1, 1, ParamGrid::one_d(8), 256));
    let (bytes, _) = encode(&input, Target::Ratio(384.0), &EncodeOptions::default())?;
    let c = Container::from_bytes(bytes)?;
    let mut out = vec![half::f16::ZERO; input.textures[0].layout.texels() * 4];
    let a: u64 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let mut cache = DecodeCache::new(Lifetimes { a, b: 1000 });
    let t = std::time::Instant::now();
    let n: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    for i in 0..n {
        cache.decode_leaf_all(&c, 0, 0, [i % 8, 0], &mut out)?;
        cache.end_frame();
        cache.end_frame();
    }
    println!(
        "{:.3} ms per leaf EM (leaf level decoded, coarse levels cached)",
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    );
    Ok(())
}
