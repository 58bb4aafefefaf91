//! `engine compile`'s command line.

use super::parse_size;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct CompileArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Where the compiled files go (and shards' files are merged from)
    /// [default: out/<scene>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Frame size as WIDTHxHEIGHT (of the targets and probe renders).
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Compile only shard I of N (0-based): whole chains of 10 samples,
    /// dealt round robin; bit-identical to one process's maps.
    #[arg(long, value_parser = parse_shard, conflicts_with_all = ["merge", "ship"])]
    pub shard: Option<engine::compile::shard::Shard>,
    /// Finish a farmed compile: room light maps and the container from
    /// the maps every shard wrote into --out; fails if a sample is missing.
    #[arg(long)]
    pub merge: bool,
    /// Also copy the compiled container and room light maps (a glass
    /// scene: its per-sample shell maps' container and room light maps) into DIR
    /// (`assets/compiled/<scene>` regenerates the shipped scene).
    #[arg(long)]
    pub ship: Option<PathBuf>,
    /// Only check the compiled scene shipped in assets/compiled/ against
    /// today's inputs (writes nothing; fails when stale).
    #[arg(long, conflicts_with_all = ["shard", "merge", "ship"])]
    pub check_shipped: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
    /// Turn the Khronos validation layer on for the probe renders.
    #[arg(long)]
    pub validate: bool,
}

fn parse_shard(s: &str) -> Result<engine::compile::shard::Shard, String> {
    engine::compile::shard::Shard::parse(s).map_err(|e| e.to_string())
}
