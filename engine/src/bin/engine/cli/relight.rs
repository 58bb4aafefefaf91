//! `engine relight`'s command line.

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct RelightArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Panorama size as WIDTHxHEIGHT (cylindrical, square pixels at the horizon).
    #[arg(long, default_value = "1024x256", value_parser = super::parse_size)]
    pub size: (u32, u32),
    /// Light grid: Gauss–Legendre rings x azimuths (≥ 5x9 for exact k = 25 projection).
    #[arg(long, default_value = "8x16", value_parser = super::parse_grid)]
    pub grid: (u32, u32),
    /// Samples per panorama texel for every traced light direction.
    #[arg(long, default_value_t = 2)]
    pub spp: u32,
    /// Diffuse bounces after the first hit (indirect light).
    #[arg(long, default_value_t = 1)]
    pub bounces: u32,
    /// Random seed of the traces.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Store the SH maps through the codec at this compression ratio (against
    /// 32-bit floats; above 1 and at most 100,000) and play the decoded maps; the raw maps' scores are
    /// reported beside them.
    #[arg(long, default_value_t = engine::relight::codec::DEFAULT_RATIO)]
    pub ratio: f64,
    /// Play the raw (uncompressed) maps instead.
    #[arg(long)]
    pub raw: bool,
    /// Timed frames per measurement (after 5 warm-up frames; 1 to 100,000).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Output folder (the cached grid and the images go to <out>/relight)
    /// [default: out/<scene>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the report here as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Turn the Khronos validation layer on.
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
}
