//! Writes small valid containers as seeds for the fuzz corpus:
//! `cargo run --release -p codec --example fuzz_seed -- codec/fuzz/corpus/container`
use codec::synth::{SynthSpec, scene};
use codec::{EncodeOptions, ParamGrid, Target, encode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).ok_or("usage: fuzz_seed DIR")?;
    let specs = [
        (
            SynthSpec {
                faces: 1,
                channels: 3,
                ..SynthSpec::cube(1, 1, ParamGrid::one_d(3), 4)
            },
            600u64,
        ),
        (
            SynthSpec {
                faces: 1,
                ..SynthSpec::cube(2, 1, ParamGrid::one_d(10), 8)
            },
            1500,
        ),
        (
            SynthSpec {
                faces: 6,
                ..SynthSpec::cube(1, 1, ParamGrid::two_d(3, 2), 4)
            },
            6000,
        ),
    ];
    for (i, (spec, bytes)) in specs.iter().enumerate() {
        let (b, _) = encode(
            &scene(spec),
            Target::Bytes(*bytes),
            &EncodeOptions::default(),
        )?;
        std::fs::write(format!("{dir}/seed{i}"), &b)?;
        println!("seed{i}: {} bytes", b.len());
    }
    Ok(())
}
