//! The main job (no subcommand): compile what is missing, play the default
//! path; with `--score N`, score N of its frames against the tracer.

use crate::cli::PlayArgs;
use anyhow::{Result, bail};
use engine::eval::path_score;

pub fn run(args: &PlayArgs) -> Result<String> {
    if args.score.is_some() {
        check_score(args)?;
    }
    let played = engine::play::play(&args.place(), &args.options())?;
    let mut text = played.report.table();
    if let Some(video) = played.video {
        text += &video.describe();
        text.push('\n');
    }
    match args.score {
        Some(count) => {
            let scene = inference::scene::Scene::load(&args.scene)?;
            let (out, frames) = (&played.out, played.frames);
            text += &path_score::score_path(&scene, out, args.size, frames, count)?.table();
        }
        // An earlier run's scores would describe other frames.
        None => path_score::remove_scores(&played.out)?,
    }
    Ok(text)
}

/// `--score` mistakes, refused before anything plays.
fn check_score(args: &PlayArgs) -> Result<()> {
    if args.no_capture {
        bail!("--score with --no-capture: scoring reads the frames the run writes; drop one");
    }
    if args.light_path.is_some() {
        bail!(
            "--score with --light-path: the references are traced under the scene's own \
             lights, not the moving one; drop one"
        );
    }
    let scene = inference::scene::Scene::load(&args.scene)?;
    path_score::check(&scene, args.size)
}
