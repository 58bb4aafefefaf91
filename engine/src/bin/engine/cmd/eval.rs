//! `engine eval`: the speed/accuracy table against the tracer.

use crate::cli::{EvalArgs, device};
use anyhow::Result;
use engine::eval::{EvalOptions, eval};
use engine::options::RunPlace;
use engine::relight::GridSettings;

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
        relight: GridSettings::new(
            args.relight_size,
            args.relight_grid,
            args.relight_spp,
            1,
            0,
            "--relight-size, --relight-grid, --relight-spp",
        )?,
    };
    eval(&place, &opts)
}
