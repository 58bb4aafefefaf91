//! The main job (no subcommand): compile what is missing, play the default path.

use crate::cli::PlayArgs;
use anyhow::Result;

pub fn run(args: &PlayArgs) -> Result<String> {
    Ok(engine::play::play(&args.place(), &args.options())?.table())
}
