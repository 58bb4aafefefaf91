//! The `engine` binary's command line: clap structures, and how each
//! becomes the library's typed options.

use clap::{Args, Parser, Subcommand};
use engine::backend::DeviceOptions;
use engine::options::{LightPathOptions, Mode, PlayOptions, RunPlace};
use std::path::PathBuf;

pub use parse::{
    parse_degrees, parse_elevation, parse_grid, parse_ratio, parse_size, parse_tau, parse_threads,
    parse_view_blend, parse_weight,
};

mod bench;
mod codec;
mod compile;
mod export;
mod parse;
mod pem;
mod place;
mod relight;
pub use bench::BenchArgs;
pub use codec::{CodecReportArgs, EncodeArgs};
pub use compile::CompileArgs;
pub use export::ExportArgs;
pub use pem::PemArgs;
pub use place::PlaceArgs;
pub use relight::RelightArgs;

#[derive(Parser, Debug)]
#[command(
    name = "engine",
    version,
    about = "Replays ray-traced imagery as parameterized environment maps, headless on Vulkan (lavapipe by default)."
)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Without a subcommand: play the scene (the main job).
    #[command(flatten)]
    pub play: PlayArgs,
}

impl Cli {
    /// Parses the process's arguments. Every command lets a negative number
    /// reach its flag's own parser (`--frames -1` is then refused naming
    /// `--frames` and its range, not as an unknown argument `-1`).
    pub fn parse_args() -> Self {
        use clap::{CommandFactory, FromArgMatches};
        let command = Cli::command()
            .allow_negative_numbers(true)
            .mut_subcommands(|c| c.allow_negative_numbers(true));
        let matches = command.get_matches();
        Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
    }
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Measure the bare, static-EM and layered-PEM frames, the PEM built up
    /// pass by pass, at the same views between samples, interleaved in one
    /// run (--frames = frames per view); on a glass scene the hybrid frame
    /// at τ = 3, 5 and 10, forward and from the traced shell; writes
    /// bench.json.
    Bench(BenchArgs),
    /// Infer each reflector's layered environment maps for orbit samples by
    /// least squares against the traced layers (tracing them if missing),
    /// beside the forward-mapping baseline; writes maps and report.json.
    Infer(InferArgs),
    /// Compress every sample's inferred maps into one container per scene.
    Encode(EncodeArgs),
    /// Measure a container: ratio, PSNR, decode time, baselines (JSON).
    ///
    /// Needs the uncompressed inferred maps the container was encoded from
    /// (`engine infer --scene <scene> --all`): it compares the decoded
    /// container against them, and looks for them in out/<scene>/infer
    /// unless --infer-dir says where they are.
    CodecReport(CodecReportArgs),
    /// Compile what the main job plays (traces, maps, room light maps,
    /// container) without playing: whole, one shard of the samples for a
    /// farmed compile (--shard I/N), or the merge that finishes one.
    Compile(CompileArgs),
    /// Measure every mode and speed/accuracy knob against the tracer on
    /// views on the orbit, between samples and above the orbit plane;
    /// writes eval.json and tradeoff.png.
    Eval(EvalArgs),
    /// Choose where a scene needs its viewpoint samples (a 1D orbit's
    /// azimuth lines; a 2D grid's rings with --rings, or its lines and
    /// rings together with --grid): refine from a few even lines, splitting the interval whose middle view (blended from its
    /// ends, on the dense compile) scores worst against the tracer, until
    /// every middle reaches --target-db or --max-samples are placed; scores
    /// an even placement of as many samples the same way; writes
    /// placement.json and placement.png.
    Place(PlaceArgs),
    /// Write every sample's inferred maps as KTX2 files other engines load
    /// (RGBA float32; cube maps with all their MIP levels) and maps.json
    /// (each sample's viewpoint, each map's EM geometry).
    Export(ExportArgs),
    /// Ray-trace the gold-standard layers of one parameter sample, a free view or all samples
    /// (CPU, no Vulkan): one multi-layer EXR and a tone-mapped PNG per image.
    Trace(TraceArgs),
    /// Relight the room's cylindrical panorama with spherical harmonics: trace
    /// it under a grid of light directions (cached), project onto k = 9, 16,
    /// 25 SH maps, relight on the GPU, time it and score it against the
    /// tracer at held-out light directions.
    Relight(RelightArgs),
}

#[derive(Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("what").required(true).args(["sample", "all", "view_angle"])))]
pub struct TraceArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Orbit sample to trace (0-based; a scene has at most 4,096).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..4096))]
    pub sample: Option<u32>,
    /// Trace every orbit sample, skipping those already traced with the same inputs.
    #[arg(long)]
    pub all: bool,
    /// Trace a free view at this orbit azimuth in degrees (off the sample grid).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_degrees)]
    pub view_angle: Option<f32>,
    // Without --view-angle refused by `cmd::trace`: clap's `requires` lets
    // it through beside the required group's --sample or --all.
    /// With --view-angle: elevation above the orbit in degrees [default: 0].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_elevation)]
    pub elevation: Option<f32>,
    /// Samples per pixel [default: 16].
    #[arg(long)]
    pub spp: Option<u32>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Output folder [default: out/<scene>/trace].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Random seed; the same seed gives bit-identical images.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads, 1 to 256 [default: all cores]; does not change the images.
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
}

#[derive(Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("which").required(true).args(["sample", "all", "diffuse"])))]
pub struct InferArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Orbit sample to infer (0-based).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..4096))]
    pub sample: Option<u32>,
    /// Every orbit sample, skipping those already inferred from the same inputs.
    #[arg(long)]
    pub all: bool,
    /// Infer one view-independent texture for this diffuse object from its
    /// traced diffuse layers at --views, stacked into one solve.
    #[arg(long)]
    pub diffuse: Option<String>,
    /// Orbit samples stacked by --diffuse, comma-separated (e.g. 0,33,66,99).
    #[arg(long, value_delimiter = ',', default_value = "0,33,66,99")]
    pub views: Vec<u32>,
    /// Texture size (square, power of two) for --diffuse.
    #[arg(long, default_value_t = 256)]
    pub texture_size: u32,
    /// Output folder [default: out/<scene>/infer].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Where traced targets are read from and written to [default: out/<scene>/trace].
    #[arg(long)]
    pub trace_dir: Option<PathBuf>,
    /// Image size of the targets and probe renders, as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Cube-map size for every EM [default: the scene's [objects.em] resolution].
    #[arg(long)]
    pub em_size: Option<u32>,
    /// Also infer one sphere-at-infinity EM per reflector,
    /// `<object>.specular_sphere`: its whole specular appearance (local over
    /// distant, before Fresnel, shaded like the distant layer), the single
    /// PEM the layered one is compared with. Other maps keep their keys, so
    /// `--all --sphere` after `--all` infers only the sphere EMs.
    #[arg(long, conflicts_with = "diffuse")]
    pub sphere: bool,
    /// Samples per pixel when a target must be traced first [default: 16].
    #[arg(long)]
    pub spp: Option<u32>,
    /// Pyramidal regularization weight ε_f.
    #[arg(long, default_value_t = 0.1, value_parser = parse_weight)]
    pub eps_f: f32,
    /// Turn the Khronos validation layer on (see the main command).
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
}

#[derive(Args, Debug, Clone)]
pub struct EvalArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Output folder for eval.json, tradeoff.png and pictures [default: out/<scene>/eval].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Frame size as WIDTHxHEIGHT (the maps' inference size is best).
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Views per category (on the orbit, between samples, above the plane),
    /// spread evenly along the orbit.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=50))]
    pub views: u32,
    /// Elevations of the "above" views over the orbit plane, in degrees,
    /// comma-separated (the `*_above` fields report the first).
    #[arg(
        long,
        value_delimiter = ',',
        default_values_t = [10.0, 20.0, 30.0],
        value_parser = parse_elevation
    )]
    pub elevation: Vec<f32>,
    /// Samples per pixel of the traced references (1 to 4096).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub spp: u32,
    /// Timed frames per view and row (after one untimed frame; 1 to 1,000).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeats: u32,
    /// Only these rows (labels as printed, comma-separated) [default: all].
    #[arg(long, value_delimiter = ',')]
    pub rows: Vec<String>,
    /// Where the scene's compiled inputs live (trace, infer, container) [default: out/<scene>].
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// The `relight` rows: panorama size as WIDTHxHEIGHT (as `engine relight --size`).
    #[arg(long, default_value = "1024x256", value_parser = parse_size)]
    pub relight_size: (u32, u32),
    /// The `relight` rows: light grid, rings x azimuths (as `engine relight --grid`).
    #[arg(long, default_value = "8x16", value_parser = parse_grid)]
    pub relight_grid: (u32, u32),
    /// The `relight` rows: samples per panorama texel (as `engine relight --spp`).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub relight_spp: u32,
    /// Turn the Khronos validation layer on.
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
}

#[derive(Args, Debug, Clone)]
pub struct PlayArgs {
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Frames along the default path: through every orbit sample, then
    /// rising above the orbit plane [default: 1.5 per viewpoint sample].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: Option<u32>,
    /// Frame size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Output folder for frames, perf.json and the compiled maps
    /// [default: out/<scene>]; the engine writes only into folders it made
    /// or that were empty.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// What each frame draws [default: hybrid for a scene with a glass
    /// object, layered-pem otherwise].
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,
    #[command(flatten)]
    pub pem: PemArgs,
    /// Turn the Khronos validation layer on; the run ends with
    /// `validation messages: N` and fails when N > 0.
    #[arg(long)]
    pub validate: bool,
    /// Vulkan device to use (substring of its name; "lavapipe" finds llvmpipe) [default: lavapipe].
    #[arg(long, env = "ENGINE_DEVICE")]
    pub device: Option<String>,
    /// Untimed frames first (lavapipe compiles shaders at the first draw).
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Also write each frame as linear float EXR.
    #[arg(long)]
    pub exr: bool,
    /// Write no frames (only perf.json): for benchmarks.
    #[arg(long)]
    pub no_capture: bool,
    /// After playing, score N frames spread along the path from its first
    /// frame to its last (1 to 1,000) against the ray tracer: each frame as
    /// written to PNG against its view traced at 16 spp (about 7 s a view at
    /// 640x480 on two cores; cached under <out>/reference), display PSNR and
    /// FLIP over every pixel as `engine eval` scores them; writes score.json
    /// and score.png (the worst frame: engine | tracer | difference ×4).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub score: Option<u32>,
    /// Write no video of the path beside the frames (an H.264 MP4 when
    /// ffmpeg is on PATH, else an animated PNG).
    #[arg(long)]
    pub no_video: bool,
    /// Samples per pixel of `--mode trace` frames.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub trace_spp: u32,
    /// Seed of `--mode trace` frames (the same seed gives the same image;
    /// another, an independent one).
    #[arg(long, default_value_t = 0)]
    pub trace_seed: u64,
    /// Move a light along the path while playing (static-EM frames: the
    /// reflector shows the room relit for the light by spherical harmonics,
    /// the room is lit by it; the scene's lights are dark).
    #[arg(long, value_enum)]
    pub light_path: Option<engine::relight::light_path::LightPath>,
    /// With --light-path: the relightable panorama's size as WIDTHxHEIGHT
    /// (1024x512 reaches 63° above and below the horizon).
    #[arg(long, default_value = "1024x512", value_parser = parse_size)]
    pub light_path_size: (u32, u32),
    /// With --light-path: the light grid, rings x azimuths.
    #[arg(long, default_value = "8x16", value_parser = parse_grid)]
    pub light_path_grid: (u32, u32),
    /// With --light-path: samples per panorama texel.
    #[arg(long, default_value_t = 2)]
    pub light_path_spp: u32,
    /// Ignore the compiled scene shipped in assets/compiled/ and run the
    /// full pipeline (trace, infer, room light maps, encode) under --out.
    #[arg(long)]
    pub recompile: bool,
}

impl PlayArgs {
    /// Where the run happens.
    pub fn place(&self) -> RunPlace {
        RunPlace {
            scene: self.scene.clone(),
            out: self.out.clone(),
            device: device(&self.device, self.validate),
            size: self.size,
            recompile: self.recompile,
        }
    }

    /// What the main job draws and keeps.
    pub fn options(&self) -> PlayOptions {
        PlayOptions {
            mode: self.mode,
            pem: self.pem.options(),
            frames: self.frames,
            warmup: self.warmup,
            capture: !self.no_capture,
            exr: self.exr,
            video: !self.no_video,
            trace: engine::options::TraceFrames {
                spp: self.trace_spp,
                seed: self.trace_seed,
            },
            light_path: self.light_path.map(|path| LightPathOptions {
                path,
                size: self.light_path_size,
                grid: self.light_path_grid,
                spp: self.light_path_spp,
            }),
        }
    }
}

/// The device options of `--device` and `--validate`.
pub fn device(name: &Option<String>, validate: bool) -> DeviceOptions {
    DeviceOptions {
        device_name: name.clone(),
        validate,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_ratios_parse_and_reject() {
        assert_eq!(parse_ratio("384"), Ok(384.0));
        assert_eq!(parse_ratio(" 1600.5"), Ok(1600.5));
        for bad in ["1", "0.5", "-3", "inf", "NaN", "x", ""] {
            assert!(parse_ratio(bad).is_err(), "{bad}");
        }
        let cli =
            Cli::try_parse_from(["engine", "codec-report", "f.ptxc", "--json", "o.json"]).unwrap();
        let Some(Command::CodecReport(a)) = cli.command else {
            panic!("not codec-report");
        };
        assert!(!a.curve);
        assert_eq!(a.curve_ratios, vec![100.0, 200.0, 400.0, 800.0, 1600.0]);
        let cli = Cli::try_parse_from([
            "engine",
            "codec-report",
            "f.ptxc",
            "--json",
            "o.json",
            "--curve",
            "--curve-ratios",
            "50,300",
        ])
        .unwrap();
        let Some(Command::CodecReport(a)) = cli.command else {
            panic!("not codec-report");
        };
        assert!(a.curve);
        assert_eq!(a.curve_ratios, vec![50.0, 300.0]);
        assert!(
            Cli::try_parse_from([
                "engine",
                "codec-report",
                "f.ptxc",
                "--json",
                "o.json",
                "--curve-ratios",
                "50,0.5",
            ])
            .is_err()
        );
    }

    #[test]
    fn cli_is_well_formed() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
