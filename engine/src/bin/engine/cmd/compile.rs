//! `engine compile`: what the main job plays, compiled without playing.

use crate::cli::{CompileArgs, device};
use anyhow::Result;
use engine::compile::scene::{Part, check_shipped, compile_scene};
use engine::options::RunPlace;

pub fn run(args: &CompileArgs) -> Result<String> {
    let place = RunPlace {
        scene: args.scene.clone(),
        out: args.out.clone(),
        device: device(&args.device, args.validate),
        size: args.size,
        recompile: true,
    };
    if args.check_shipped {
        return check_shipped(&place);
    }
    let part = match (args.shard, args.merge) {
        (Some(shard), _) => Part::Shard(shard),
        (None, true) => Part::Merge,
        (None, false) => Part::Whole,
    };
    compile_scene(&place, part, args.ship.as_deref())
}
