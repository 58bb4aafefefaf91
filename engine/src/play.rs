//! The main job: render frames along the scene's orbit, capture them, and
//! report per-pass counters.

use crate::backend::{DeviceOptions, create_device};
use crate::capture;
use crate::cli::{Mode, PlayArgs};
use crate::perf::{PerfLog, PerfReport};
use crate::renderer::{FrameMode, Renderer};
use anyhow::{Context, Result, bail};
use inference::scene::Scene;
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

/// The orbit angle of frame `i` of `frames`, spread over the samples' span.
pub fn frame_angle(scene: &Scene, i: u32, frames: u32) -> f32 {
    let orbit = &scene.orbit;
    let span = orbit.step_deg * orbit.samples.saturating_sub(1) as f32;
    if frames <= 1 {
        orbit.start_deg
    } else {
        orbit.start_deg + span * i as f32 / (frames - 1) as f32
    }
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
    let mode = match args.mode {
        Mode::StaticEm => FrameMode::StaticEm,
        Mode::Bare => FrameMode::Bare,
    };
    let frames = args.frames.unwrap_or(scene.orbit.samples);

    let first_eye = scene.orbit.eye(frame_angle(&scene, 0, frames), 0.0);
    for _ in 0..args.warmup {
        renderer.frame(mode, first_eye, scene.orbit.view(first_eye))?;
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
        let eye = scene.orbit.eye(frame_angle(&scene, i, frames), 0.0);
        let start = Instant::now();
        let stats = renderer.frame(mode, eye, scene.orbit.view(eye))?;
        log.record(
            start.elapsed().as_secs_f64() * 1e3,
            &stats.passes,
            stats.cpu,
        );
        if !args.no_capture && send.send((i, renderer.pixels()?)).is_err() {
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
