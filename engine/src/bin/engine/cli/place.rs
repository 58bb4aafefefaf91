//! `engine place`'s command line.

use super::parse_size;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct PlaceArgs {
    /// A built-in scene's name or the path of a .toml scene file whose
    /// samples are the dense lines placement chooses from: every ring keeps
    /// every line (`ring_line_every = 1`; brass and teapot_rings do, the
    /// default teapot's sparse rings do not).
    #[arg(long)]
    pub scene: String,
    /// Where the scene's dense compile lives (compiled there if missing) [default: out/<scene>].
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Output folder for placement.json, placement.png and the traced views [default: <data>/place].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Reflector PSNR every view half way between placed samples should reach, dB.
    #[arg(long, default_value_t = 42.0, allow_hyphen_values = true, value_parser = super::parse::parse_db)]
    pub target_db: f64,
    /// At most this many samples (the budget) [default: the dense lines].
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..))]
    pub max_samples: Option<u32>,
    /// At most this many bytes of map container, at the dense container's
    /// bytes per sample (the codec codes at a fixed ratio) [default: no limit].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1_000_000_000_000))]
    pub max_bytes: Option<u64>,
    /// At most this many minutes of compile (trace, maps, container), at the
    /// dense compile's recorded minutes per sample [default: no limit].
    #[arg(long, value_parser = positive_minutes)]
    pub max_minutes: Option<f64>,
    /// Place the elevation rings of a scene with rings (every ring keeps
    /// all its azimuth lines) instead of the azimuth lines of a 1D orbit.
    #[arg(long, conflicts_with = "grid")]
    pub rings: bool,
    /// Place the azimuth lines and the rings of a scene with rings
    /// together: each step splits the worst interval of either axis whose
    /// samples still fit the budget (--max-samples counts samples).
    #[arg(long)]
    pub grid: bool,
    /// Lines (or rings) placed evenly before measuring, both ends included
    /// (with --grid, this many of each).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(2..))]
    pub start: u32,
    /// Samples per pixel of the traced views (as `engine eval --spp`).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub spp: u32,
    /// Frame size as WIDTHxHEIGHT (the maps' inference size is best).
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Turn the Khronos validation layer on.
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
}

fn positive_minutes(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(m) if m.is_finite() && m > 0.0 => Ok(m),
        _ => Err(format!("{s:?} (expected a positive number of minutes)")),
    }
}
