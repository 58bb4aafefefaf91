//! `engine eval`: the speed/accuracy table against the tracer.

use crate::cli::{EvalArgs, device};
use anyhow::Result;
use engine::eval::{EvalOptions, eval};
use engine::options::RunPlace;

pub fn run(args: &EvalArgs) -> Result<String> {
    let place = RunPlace {
        scene: args.scene.clone(),
        out: args.data.clone(),
        device: device(&args.device, args.validate),
        size: args.size,
        recompile: false,
    };
    let opts = EvalOptions {
        out: args.out.clone(),
        views: args.views,
        elevations: args.elevation.clone(),
        spp: args.spp,
        repeats: args.repeats,
        rows: args.rows.clone(),
    };
    eval(&place, &opts)
}
