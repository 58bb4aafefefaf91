//! The main job (no subcommand): compile what is missing, play the default
//! path; with `--score N`, score N of its frames against the tracer.

use crate::cli::PlayArgs;
use anyhow::{Result, bail};
use engine::eval::path_score;
use inference::scene::Scene;

pub fn run(args: &PlayArgs) -> Result<String> {
    // Checked before anything plays; scored after.
    let scoring = match args.score {
        Some(count) => Some((scene_to_score(args)?, count)),
        None => None,
    };
    let played = engine::play::play(&args.place(), &args.options())?;
    let mut text = played.report.table();
    if let Some(video) = played.video {
        text += &video.describe();
        text.push('\n');
    }
    match scoring {
        Some((scene, count)) => {
            let (out, frames) = (&played.out, played.frames);
            text += &path_score::score_path(&scene, out, args.size, frames, count)?.table();
        }
        // An earlier run's scores would describe other frames.
        None => path_score::remove_scores(&played.out)?,
    }
    Ok(text)
}

/// The scene `--score` traces its references of, its mistakes refused.
fn scene_to_score(args: &PlayArgs) -> Result<Scene> {
    if args.no_capture {
        bail!("--score with --no-capture: scoring reads the frames the run writes; drop one");
    }
    if args.light_path.is_some() {
        bail!(
            "--score with --light-path: the references are traced under the scene's own \
             lights, not the moving one; drop one"
        );
    }
    let scene = Scene::load(&args.scene)?;
    path_score::check(&scene, args.size)?;
    Ok(scene)
}
