//! What the main job compiles before it can play PEMs: the traced gold
//! standard, the inferred maps of every sample and the compressed
//! container — each only when missing, each with its own progress bars and
//! cache, so a second run starts playing at once.

use crate::cli::{Cli, Command, EncodeArgs, InferArgs, Maps, PlayArgs};
use crate::pem::source::{MapLayer, MapSource, sample_path};
use anyhow::{Context, Result, bail};
use clap::Parser;
use inference::scene::Scene;
use std::path::{Path, PathBuf};

/// Where the compiled inputs of a run live, under its output folder.
pub struct Compiled {
    pub infer_dir: PathBuf,
    pub trace_dir: PathBuf,
    pub container: PathBuf,
}

impl Compiled {
    pub fn paths(args: &PlayArgs, scene: &Scene, out: &Path) -> Self {
        Self {
            infer_dir: args
                .pem
                .infer_dir
                .clone()
                .unwrap_or_else(|| out.join("infer")),
            trace_dir: out.join("trace"),
            container: args
                .pem
                .container
                .clone()
                .unwrap_or_else(|| out.join(format!("{}.ptxc", scene.name))),
        }
    }
}

/// The map source for `layers`, compiling whatever is missing first.
/// Sphere-at-infinity maps are not in the container: they play from EXR.
pub fn map_source(
    args: &PlayArgs,
    scene: &Scene,
    out: &Path,
    layers: &[MapLayer],
) -> Result<MapSource> {
    let paths = Compiled::paths(args, scene, out);
    let sphere = layers.contains(&MapLayer::Sphere);
    if !maps_complete(scene, &paths.infer_dir, layers) {
        infer_all(args, scene, &paths, sphere)?;
        if !maps_complete(scene, &paths.infer_dir, layers) {
            bail!(
                "{}: inference finished but maps are still missing",
                paths.infer_dir.display()
            );
        }
    }
    if args.pem.maps == Maps::Exr || sphere {
        return Ok(MapSource::exr(&paths.infer_dir));
    }
    if !paths.container.is_file() || older_than_maps(&paths.container, scene, &paths.infer_dir) {
        let encode = |bytes: Option<u64>| {
            crate::codec_cmd::encode(&EncodeArgs {
                scene: args.scene.clone(),
                ratio: None,
                bytes,
                infer_dir: Some(paths.infer_dir.clone()),
                out: paths.container.clone(),
            })
        };
        // The default ratio; maps too small for it (test scenes) get the
        // smallest container the codec can write.
        let text = match encode(None) {
            Err(e) => match e.downcast_ref::<codec::CodecError>() {
                Some(&codec::CodecError::BudgetTooSmall { minimum, .. }) => {
                    eprintln!("maps too small for the default ratio: encoding at {minimum} bytes");
                    encode(Some(minimum))?
                }
                _ => return Err(e),
            },
            ok => ok?,
        };
        eprint!("{text}");
    }
    MapSource::container(scene, &paths.container)
}

/// Whether some map the container holds was written after it (re-inferred).
fn older_than_maps(container: &Path, scene: &Scene, dir: &Path) -> bool {
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let Some(built) = modified(container) else {
        return true;
    };
    let layers = [MapLayer::Distant, MapLayer::Local, MapLayer::Ptm];
    scene.objects.iter().filter(|o| o.em.is_some()).any(|o| {
        (0..scene.orbit.samples).any(|k| {
            layers
                .iter()
                .filter_map(|&l| modified(&sample_path(dir, k, &o.name, l)))
                .any(|t| t > built)
        })
    })
}

/// Every sample has every map `layers` names.
fn maps_complete(scene: &Scene, dir: &Path, layers: &[MapLayer]) -> bool {
    scene.objects.iter().filter(|o| o.em.is_some()).all(|o| {
        (0..scene.orbit.samples).all(|k| {
            layers
                .iter()
                .all(|&l| sample_path(dir, k, &o.name, l).is_file())
        })
    })
}

/// `engine infer --all` (tracing what is missing) at the run's size.
fn infer_all(args: &PlayArgs, scene: &Scene, paths: &Compiled, sphere: bool) -> Result<()> {
    eprintln!(
        "{}: inferred maps missing in {}: tracing and inferring every sample (cached; a re-run resumes)",
        scene.name,
        paths.infer_dir.display()
    );
    let size = format!("{}x{}", args.size.0, args.size.1);
    let mut argv: Vec<String> = [
        "engine",
        "infer",
        "--all",
        "--scene",
        &args.scene,
        "--size",
        &size,
    ]
    .map(String::from)
    .to_vec();
    for (flag, path) in [
        ("--out", &paths.infer_dir),
        ("--trace-dir", &paths.trace_dir),
    ] {
        argv.push(flag.into());
        argv.push(path.display().to_string());
    }
    if let Some(device) = &args.device {
        argv.extend(["--device".into(), device.clone()]);
    }
    if sphere {
        argv.push("--sphere".into());
    }
    let cli = Cli::try_parse_from(&argv).context("building the infer command")?;
    let Some(Command::Infer(infer)) = cli.command else {
        bail!("internal: `engine infer` did not parse as itself");
    };
    let infer: InferArgs = infer;
    let text = crate::infer_cmd::infer(&infer)?;
    eprint!("{text}");
    Ok(())
}
