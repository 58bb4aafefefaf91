//! `engine place`: where a scene needs its viewpoint samples (azimuth
//! lines, or rings with `--rings`).

use crate::cli::{PlaceArgs, device};
use anyhow::Result;
use engine::options::RunPlace;
use engine::place::{Axis, PlaceOptions, place};

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
        axis: if args.rings {
            Axis::Rings
        } else {
            Axis::Azimuth
        },
    };
    place(&run, &opts)
}
