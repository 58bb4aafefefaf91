//! The main job (no subcommand): compile what is missing, play the default
//! path; with `--score N`, score N of its frames against the tracer.

use crate::cli::PlayArgs;
use anyhow::{Result, bail};

pub fn run(args: &PlayArgs) -> Result<String> {
    if args.score.is_some() && args.no_capture {
        bail!("--score with --no-capture: scoring reads the frames the run writes; drop one");
    }
    let played = engine::play::play(&args.place(), &args.options())?;
    let mut text = played.report.table();
    if let Some(video) = played.video {
        text += &video.describe();
        text.push('\n');
    }
    if let Some(count) = args.score {
        let scene = inference::scene::Scene::load(&args.scene)?;
        let score = engine::eval::path_score::score_path(
            &scene,
            &played.out,
            args.size,
            played.frames,
            count,
        )?;
        text += &score.table();
    }
    Ok(text)
}
