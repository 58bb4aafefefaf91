//! `engine bench`: every method's frame at the same views, interleaved.

use crate::cli::PlayArgs;
use anyhow::Result;
use engine::bench::{BenchOptions, bench};

pub fn run(args: &PlayArgs) -> Result<String> {
    let opts = BenchOptions {
        frames_per_view: args.frames.unwrap_or(25),
        warmup: args.warmup,
        pem: args.pem.options(),
    };
    Ok(bench(&args.place(), &opts)?.table())
}
