//! `engine encode` and `engine codec-report` command lines.

use super::{parse_ratio, parse_size};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct EncodeArgs {
    /// A built-in scene's name (teapot) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Target compression ratio against 32-bit floats, above 1 and at most 100,000 [default: 384].
    #[arg(long, conflicts_with = "bytes")]
    pub ratio: Option<f64>,
    /// Target container size in bytes.
    #[arg(long)]
    pub bytes: Option<u64>,
    /// Where `engine infer --all` wrote the maps [default: out/<scene>/infer].
    #[arg(long)]
    pub infer_dir: Option<PathBuf>,
    /// The container file to write.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug, Clone)]
pub struct CodecReportArgs {
    /// The container to measure.
    pub file: PathBuf,
    /// Where to write the JSON report.
    #[arg(long)]
    pub json: PathBuf,
    /// A built-in scene's name (teapot) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// The uncompressed maps the container was encoded from, which the
    /// report compares it against; they must exist (`engine infer --scene
    /// <scene> --all` writes them) [default: out/<scene>/infer].
    #[arg(long)]
    pub infer_dir: Option<PathBuf>,
    /// Traced targets for the rendered-frame PSNR [default: out/<scene>/trace].
    #[arg(long)]
    pub trace_dir: Option<PathBuf>,
    /// Size the targets were traced at, as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Measure rendered frames at every Nth sample (0: skip; the MPEG-view
    /// baseline uses the same frames and pixels, so it is skipped too).
    #[arg(long, default_value_t = 10)]
    pub frames_every: u32,
    /// Also encode the scene at each of --curve-ratios and measure the
    /// codec and the baselines at the same bytes: ratio-against-PSNR curves
    /// in the JSON (`curves`). Takes one encoder analysis plus the
    /// baselines' encodings (minutes).
    #[arg(long)]
    pub curve: bool,
    /// Compression ratios of the curve points (against 32-bit floats).
    #[arg(long, value_delimiter = ',', default_value = "100,200,400,800,1600", value_parser = parse_ratio)]
    pub curve_ratios: Vec<f64>,
    /// Video encoders of the MPEG-texture baselines, curves and random
    /// access, each run only when the installed ffmpeg has it (x265 and AV1
    /// take most of the report's time).
    #[arg(long, value_delimiter = ',', default_value = "x264,x265,av1")]
    pub video: Vec<VideoArg>,
    /// Turn the Khronos validation layer on for the rendered frames.
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
}

/// A video encoder by its command-line name.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum VideoArg {
    /// libx264 (`mpeg-texture`).
    X264,
    /// libx265 (`mpeg-texture-x265`).
    X265,
    /// libaom-av1 (`mpeg-texture-av1`).
    Av1,
}

impl From<VideoArg> for ::codec::report::VideoCodec {
    fn from(v: VideoArg) -> Self {
        match v {
            VideoArg::X264 => Self::X264,
            VideoArg::X265 => Self::X265,
            VideoArg::Av1 => Self::Av1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::VideoArg;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    #[test]
    fn video_encoders_default_to_all_and_parse_by_name() {
        let video = |extra: &[&str]| {
            let args = [&["engine", "codec-report", "f", "--json", "o"][..], extra].concat();
            Cli::try_parse_from(args).map(|cli| match cli.command {
                Some(Command::CodecReport(a)) => a.video,
                _ => Vec::new(),
            })
        };
        let all = [VideoArg::X264, VideoArg::X265, VideoArg::Av1];
        assert_eq!(video(&[]).ok(), Some(all.to_vec()));
        assert_eq!(video(&["--video", "x264"]).ok(), Some(vec![VideoArg::X264]));
        assert_eq!(
            video(&["--video", "av1,x265"]).ok(),
            Some(vec![VideoArg::Av1, VideoArg::X265])
        );
        assert!(video(&["--video", "vp9"]).is_err());
    }
}
