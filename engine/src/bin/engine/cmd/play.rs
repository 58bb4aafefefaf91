//! The main job (no subcommand): compile what is missing, play the default path.

use crate::cli::PlayArgs;
use anyhow::Result;

pub fn run(args: &PlayArgs) -> Result<String> {
    let played = engine::play::play(&args.place(), &args.options())?;
    let mut text = played.report.table();
    if let Some(video) = played.video {
        text += &video.describe();
        text.push('\n');
    }
    Ok(text)
}
