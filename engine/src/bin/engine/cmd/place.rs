//! `engine place`: where a scene needs its viewpoint samples (azimuth
//! lines, rings with `--rings`, or both with `--grid`).

use crate::cli::{PlaceArgs, device};
use anyhow::Result;
use engine::options::RunPlace;
use engine::place::{PlaceOptions, Placing, place};

pub fn run(args: &PlaceArgs) -> Result<String> {
    let run = RunPlace {
        scene: args.scene.clone(),
        out: args.data.clone(),
        device: device(&args.device, args.validate),
        size: args.size,
        recompile: false,
    };
    let opts = PlaceOptions {
        out: args.out.clone(),
        target_db: args.target_db,
        max_samples: args.max_samples.unwrap_or(u32::MAX),
        max_bytes: args.max_bytes,
        max_minutes: args.max_minutes,
        start: args.start,
        spp: args.spp,
        placing: if args.grid {
            Placing::Grid
        } else if args.rings {
            Placing::Rings
        } else {
            Placing::Azimuth
        },
    };
    place(&run, &opts)
}
