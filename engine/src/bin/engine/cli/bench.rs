//! `engine bench`'s command line.

use super::{PemArgs, device, parse_elevation, parse_size};
use clap::Args;
use engine::options::RunPlace;
use std::path::PathBuf;

/// `engine bench`: only what the bench reads (the variants it measures are
/// its own, so the main job's mode, capture and light-path flags are not
/// offered here to be silently ignored).
#[derive(Args, Debug, Clone)]
pub struct BenchArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Timed frames per view and variant (8 views; at most 100,000).
    #[arg(long, default_value_t = 25, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Frame size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The views' elevation above the orbit plane in degrees [default: half
    /// way to the scene's first ring above it, where four samples blend; 0
    /// on a 1D orbit].
    #[arg(long, value_parser = parse_elevation, allow_hyphen_values = true)]
    pub elevation: Option<f32>,
    /// Output folder for bench.json and the compiled maps [default:
    /// out/<scene>]; the engine writes only into folders it made or that
    /// were empty.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub pem: PemArgs,
    /// Turn the Khronos validation layer on; the run ends with
    /// `validation messages: N` and fails when N > 0.
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
    /// Untimed frames first per view and variant (lavapipe compiles
    /// shaders at the first draw; at most 100,000).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=100_000))]
    pub warmup: u32,
    /// Ignore the compiled scene shipped in assets/compiled/ and run the
    /// full pipeline (trace, infer, room light maps, encode) under --out.
    #[arg(long)]
    pub recompile: bool,
}

impl BenchArgs {
    pub fn place(&self) -> RunPlace {
        RunPlace {
            scene: self.scene.clone(),
            out: self.out.clone(),
            device: device(&self.device, self.validate),
            size: self.size,
            recompile: self.recompile,
        }
    }
}
