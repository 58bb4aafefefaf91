//! The main job: render frames along the scene's orbit, capture them, and
//! report per-pass counters.

use crate::backend::{DeviceOptions, create_device};
use crate::capture;
use crate::cli::{Mode, PlayArgs};
use crate::pem::path::{default_frames, path_view};
use crate::pem::player::{PemKind, PemSettings};
use crate::perf::{PerfLog, PerfReport};
use crate::renderer::{FrameMode, FrameStats, Renderer};
use anyhow::{Context, Result, bail};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Instant;

/// Output folder: `--out`, else `out/<scene>` under the current directory.
pub fn output_dir(args: &PlayArgs, scene: &Scene) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name))
}

/// Creates `dir` and proves it writable before any rendering starts.
pub fn prepare_output(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let probe = dir.join(".write-test");
    std::fs::write(&probe, b"")
        .with_context(|| format!("output folder {} is not writable", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// What playing and benchmarking share: the scene, a writable output
/// folder, the device and a renderer set up at the requested size.
pub struct Session {
    pub scene: Scene,
    pub out: PathBuf,
    pub device: crate::backend::Device,
    pub renderer: Renderer,
}

pub fn open_session(args: &PlayArgs) -> Result<Session> {
    let scene = Scene::load(&args.scene)?;
    let out = output_dir(args, &scene);
    prepare_output(&out)?;
    let device = create_device(&DeviceOptions {
        device_name: args.device.clone(),
        validate: args.validate,
    })?;
    let (width, height) = args.size;
    let renderer = Renderer::new(&device, &scene, width, height)
        .with_context(|| format!("setting up scene {}", scene.source.display()))?;
    Ok(Session {
        scene,
        out,
        device,
        renderer,
    })
}

pub fn play(args: &PlayArgs) -> Result<PerfReport> {
    let Session {
        scene,
        out,
        device,
        mut renderer,
    } = open_session(args)?;
    let (width, height) = args.size;
    let mut frames_from = setup_mode(args, &scene, &out, &mut renderer)?;
    let frames = args.frames.unwrap_or(default_frames(&scene.orbit));
    let eye_of = |i: u32| {
        let (azimuth, elevation) = path_view(&scene.orbit, i, frames);
        scene.orbit.eye(azimuth, elevation)
    };

    if !matches!(frames_from, FrameSource::Trace(..)) {
        for _ in 0..args.warmup {
            frames_from.frame(&mut renderer, &scene, eye_of(0))?;
        }
    }

    // Encoding PNGs takes longer than a frame: a writer thread does it.
    let (send, receive) = mpsc::channel::<(u32, Vec<[f32; 4]>)>();
    let writer_dir = out.clone();
    let write_exr = args.exr;
    let writer = std::thread::spawn(move || -> Result<(), capture::CaptureError> {
        for (i, pixels) in receive {
            let stem = writer_dir.join(format!("frame_{i:04}"));
            capture::write_png(&stem.with_extension("png"), width, height, &pixels)?;
            if write_exr {
                capture::write_exr(&stem.with_extension("exr"), width, height, &pixels)?;
            }
        }
        Ok(())
    });

    let progress = indicatif::ProgressBar::new(u64::from(frames)).with_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    progress.set_message(format!("{} {:?}", scene.name, args.mode));
    let mut log = PerfLog::default();
    for i in 0..frames {
        let start = Instant::now();
        let (stats, pixels) = frames_from.frame(&mut renderer, &scene, eye_of(i))?;
        log.record(
            start.elapsed().as_secs_f64() * 1e3,
            &stats.passes,
            stats.cpu,
        );
        if !args.no_capture && send.send((i, pixels)).is_err() {
            break; // the writer stopped: its error is reported below
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    drop(send);
    match writer.join() {
        Ok(result) => result?,
        Err(_) => bail!("the frame writer thread panicked"),
    }

    let report = log.report(
        &device.name,
        &scene.name,
        &format!("{:?}", args.mode),
        [width, height],
        &renderer.setup_timings,
    );
    let json = serde_json::to_string_pretty(&report)?;
    let perf_path = out.join("perf.json");
    let tmp = out.join(".perf.json.tmp");
    std::fs::write(&tmp, json).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &perf_path)
        .with_context(|| format!("writing {}", perf_path.display()))?;
    Ok(report)
}

/// Where a run's frames come from: the rasteriser in some mode, or the
/// tracer (the gold standard, seconds per frame).
pub enum FrameSource<'s> {
    Raster(FrameMode),
    Trace(Box<Tracer<'s>>, TraceSettings),
}

impl FrameSource<'_> {
    /// One frame from `eye` (looking at the orbit centre) and its pixels.
    pub fn frame(
        &mut self,
        renderer: &mut Renderer,
        scene: &Scene,
        eye: glam::Vec3,
    ) -> Result<(FrameStats, Vec<[f32; 4]>)> {
        match self {
            FrameSource::Raster(mode) => {
                let stats = renderer.frame(*mode, eye, scene.orbit.view(eye))?;
                Ok((stats, renderer.pixels()?))
            }
            FrameSource::Trace(tracer, settings) => {
                let image = tracer.render(eye, settings)?;
                let Some(beauty) = image.layer("beauty") else {
                    bail!("the tracer made no beauty layer");
                };
                let pixels = beauty
                    .pixels
                    .chunks_exact(3)
                    .map(|p| [p[0], p[1], p[2], 1.0])
                    .collect();
                Ok((
                    FrameStats {
                        passes: Vec::new(),
                        cpu: Default::default(),
                    },
                    pixels,
                ))
            }
        }
    }
}

/// The PEM settings `args` ask for (None for modes without PEMs).
pub fn pem_settings(args: &PlayArgs, scene: &Scene) -> Result<Option<PemSettings>> {
    let kind = match args.mode {
        Mode::LayeredPem => PemKind::Layered,
        Mode::SpherePem => PemKind::Sphere,
        Mode::Ptm => PemKind::Ptm,
        _ => return Ok(None),
    };
    let p = &args.pem;
    let mut settings = PemSettings::new(kind);
    settings.blend = !p.no_blend;
    settings.local_layer = !p.distant_only;
    settings.spacing = p.spacing;
    settings.filtering = match p.filtering {
        crate::cli::Filter::Trilinear => crate::backend::Filtering::Trilinear,
        crate::cli::Filter::Bilinear => crate::backend::Filtering::Bilinear,
        crate::cli::Filter::Nearest => crate::backend::Filtering::Nearest,
    };
    if let Some(size) = p.em_size {
        let inferred = scene
            .objects
            .iter()
            .filter_map(|o| o.em.as_ref().map(|e| e.resolution))
            .min()
            .unwrap_or(crate::renderer::DEFAULT_EM_RESOLUTION);
        if !size.is_power_of_two() || size > inferred {
            bail!("--em-size {size}: expected a power of two up to the inferred {inferred}");
        }
        settings.drop_levels = inferred.trailing_zeros() - size.trailing_zeros();
    }
    Ok(Some(settings))
}

/// Sets the renderer up for `args.mode`, compiling missing maps first.
pub fn setup_mode<'s>(
    args: &PlayArgs,
    scene: &'s Scene,
    out: &Path,
    renderer: &mut Renderer,
) -> Result<FrameSource<'s>> {
    Ok(match args.mode {
        Mode::StaticEm => FrameSource::Raster(FrameMode::StaticEm),
        Mode::Bare => FrameSource::Raster(FrameMode::Bare),
        Mode::Trace => {
            let (w, h) = args.size;
            let settings = TraceSettings {
                width: w,
                height: h,
                spp: args.trace_spp,
                ..TraceSettings::default()
            };
            FrameSource::Trace(Box::new(Tracer::new(scene)?), settings)
        }
        Mode::LayeredPem | Mode::SpherePem | Mode::Ptm => {
            let Some(settings) = pem_settings(args, scene)? else {
                bail!("internal: {:?} has no PEM settings", args.mode);
            };
            let source = crate::compile::map_source(args, scene, out, &settings.layers())?;
            renderer.set_pem(scene, settings, source)?;
            FrameSource::Raster(FrameMode::Pem)
        }
    })
}
