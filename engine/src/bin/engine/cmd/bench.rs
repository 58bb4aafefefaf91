//! `engine bench`: every method's frame at the same views, interleaved.

use crate::cli::BenchArgs;
use anyhow::Result;
use engine::bench::{BenchOptions, bench};

pub fn run(args: &BenchArgs) -> Result<String> {
    let opts = BenchOptions {
        frames_per_view: args.frames,
        warmup: args.warmup,
        pem: args.pem.options(),
        elevation_deg: args.elevation,
    };
    Ok(bench(&args.place(), &opts)?.table())
}
