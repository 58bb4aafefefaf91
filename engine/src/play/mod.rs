//! The main job: compile what is missing, render frames along the default
//! path, capture them, and report per-pass counters.

use crate::backend::create_device;
use crate::compile::CompileContext;
use crate::options::{
    LightPathOptions, Mode, PemOptions, PlayOptions, RoomShading, RunPlace, TraceFrames,
};
use crate::pem::path::{default_frames, path_view};
use crate::pem::player::{PemKind, PemSettings};
use crate::perf::{PerfLog, PerfReport};
use crate::relight::codec::{DEFAULT_RATIO, compressed};
use crate::relight::light_path::LightPath;
use crate::relight::{GridSettings, relightable};
use crate::renderer::{FrameMode, FrameStats, Renderer};
use crate::util::files::claim_dir;
use anyhow::{Context, Result, bail};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod frame_writer;

pub use frame_writer::{Captured, frame_stem};
use frame_writer::{FrameWriter, path_video};

/// SH coefficients a moving light is relit with (the paper's k = 16).
const LIGHT_PATH_K: usize = 16;

/// What playing, benchmarking and evaluating share: the scene, the output
/// folder (claimed), the device and a renderer at the run's size.
pub struct Session {
    pub place: RunPlace,
    pub scene: Scene,
    pub out: PathBuf,
    pub device: crate::backend::Device,
    pub renderer: Renderer,
}

impl Session {
    /// Loads the scene, claims the output folder (`out/<scene>` unless
    /// given), opens the device and sets the renderer up.
    pub fn open(place: &RunPlace) -> Result<Session> {
        Session::open_scene(place, Scene::load(&place.scene)?)
    }

    /// [`Session::open`] with `scene`, already loaded from `place.scene`
    /// (and checked by the caller before any folder is claimed).
    pub fn open_scene(place: &RunPlace, scene: Scene) -> Result<Session> {
        let out = place.out_dir(&scene);
        claim_dir(&out)?;
        let device = create_device(&place.device)?;
        let (width, height) = place.size;
        let renderer = Renderer::new(&device, &scene, width, height)
            .with_context(|| format!("setting up {}", scene.origin))?;
        Ok(Session {
            place: place.clone(),
            scene,
            out,
            device,
            renderer,
        })
    }
}

/// Compiling under `out` for `place`.
pub fn compile_context<'a>(
    place: &'a RunPlace,
    scene: &'a Scene,
    out: &'a Path,
) -> CompileContext<'a> {
    CompileContext {
        scene,
        scene_arg: &place.scene,
        out,
        size: place.size,
        device: &place.device,
        shipped: if place.recompile {
            None
        } else {
            crate::compile::shipped::dir(scene)
        },
    }
}

/// Sets `renderer` up for hybrid glass: the room shell, then layered
/// scenes' layers, per sample where the scene asks for per-sample maps
/// (`--traced-layers`: traced), or one-shell scenes' per-sample maps, if
/// any (`--traced-shell`: the one traced room shell, no layers).
fn setup_hybrid(ctx: &CompileContext, renderer: &mut Renderer, pem: &PemOptions) -> Result<()> {
    let deferred = pem.compositing == crate::pem::settings::Compositing::Deferred;
    crate::glass::setup(renderer, ctx.scene, ctx.out, (pem.tau, deferred))?;
    let raw = pem.maps == crate::options::Maps::Exr;
    if pem.traced_shell {
        return Ok(());
    }
    match crate::glass::layers::load(renderer, ctx.scene, ctx.out)? {
        1 => crate::compile::glass_shells::load(ctx, renderer, raw),
        _ if pem.traced_layers => Ok(()),
        _ => crate::compile::glass_shells::layered::load(ctx, renderer, raw).map(|_| ()),
    }
}

/// Sets `renderer` up for `mode`, compiling missing maps first.
pub fn setup_mode<'s>(
    ctx: &CompileContext<'s>,
    renderer: &mut Renderer,
    mode: Mode,
    pem: &PemOptions,
    trace: TraceFrames,
) -> Result<FrameSource<'s>> {
    // Every mode but the baselines (the static EM's analytic room, the
    // bare frame) and the tracer itself.
    let inferred_room = !matches!(mode, Mode::StaticEm | Mode::Bare | Mode::Trace)
        && pem.room == RoomShading::Inferred;
    let room = if inferred_room {
        let maps = crate::compile::room::room_maps(ctx)?;
        if maps.compile_s > 0.0 {
            eprintln!(
                "{}: room light maps compiled in {:.1} s",
                ctx.scene.name, maps.compile_s
            );
        }
        Some(maps)
    } else {
        None
    };
    renderer.set_room(ctx.scene, room.as_ref())?;
    Ok(match mode {
        Mode::StaticEm => {
            crate::glass::load_shell(renderer, ctx.scene, ctx.out)?;
            FrameSource::Raster(FrameMode::StaticEm)
        }
        Mode::Bare => FrameSource::Raster(FrameMode::Bare),
        Mode::Trace => {
            let (width, height) = ctx.size;
            let settings = TraceSettings {
                width,
                height,
                spp: trace.spp,
                seed: trace.seed,
                ..TraceSettings::default()
            };
            FrameSource::Trace(Box::new(Tracer::new(ctx.scene)?), settings)
        }
        Mode::Hybrid => {
            setup_hybrid(ctx, renderer, pem)?;
            FrameSource::Raster(FrameMode::Hybrid)
        }
        Mode::Rem => {
            let settings = crate::rem::sources::RemSettings {
                size: pem.rem_size,
                level: pem.rem_level,
                ..Default::default()
            };
            let maps = crate::rem::sources::source_maps(ctx.scene, ctx.out, settings)?;
            if maps.trace_s > 0.0 {
                eprintln!(
                    "{}: reflection-space source maps traced in {:.1} s ({} bytes)",
                    ctx.scene.name,
                    maps.trace_s,
                    maps.device_bytes()
                );
            }
            renderer.set_rem(ctx.scene, &maps, pem.blend)?;
            FrameSource::Raster(FrameMode::Rem)
        }
        Mode::LayeredPem | Mode::SpherePem | Mode::Ptm => {
            let settings = pem_settings(mode, pem, ctx.scene)?;
            let source = crate::compile::map_source(ctx, pem, &settings.layers())?;
            renderer.set_pem(ctx.scene, settings, source)?;
            FrameSource::Raster(FrameMode::Pem)
        }
    })
}

/// What a play wrote besides its frames.
pub struct Played {
    pub report: PerfReport,
    /// Where the frames went, and how many the path had.
    pub out: PathBuf,
    pub frames: u32,
    /// The path as a video, when frames were captured and a video asked for.
    pub video: Option<crate::video::Video>,
}

/// Plays `opts` at `place`: frames along the default path, perf.json and
/// the path as a video.
pub fn play(place: &RunPlace, opts: &PlayOptions) -> Result<Played> {
    if opts.frames == Some(0) {
        bail!("--frames 0: expected at least one frame");
    }
    let Session {
        scene,
        out,
        device,
        mut renderer,
        ..
    } = Session::open(place)?;
    let ctx = compile_context(place, &scene, &out);
    let mode = play_mode(opts, &scene)?;
    let mut source = setup_mode(&ctx, &mut renderer, mode, &opts.pem, opts.trace)?;
    let light = (opts.light_path)
        .map(|lp| setup_light_path(&scene, &out, lp, &mut renderer))
        .transpose()?;
    let renderer = &mut renderer;
    let scene = &scene;
    let (width, height) = place.size;
    let frames = opts.frames.unwrap_or(default_frames(&scene.orbit));
    let eye_of = |i: u32| {
        let (azimuth, elevation) = path_view(&scene.orbit, i, frames);
        scene.orbit.eye(azimuth, elevation)
    };
    let move_light = |renderer: &mut Renderer, i: u32| match light {
        Some((path, origin)) => renderer.move_light(path.shown(origin, i as f32 / frames as f32)),
        None => Ok(()),
    };
    if !matches!(source, FrameSource::Trace(..)) {
        move_light(renderer, 0)?;
        for _ in 0..opts.warmup {
            renderer.set_next_view(eye_of(0), scene.orbit.view(eye_of(0)));
            source.draw(renderer, scene, eye_of(0))?;
        }
    }
    let writer = FrameWriter::start(out.clone(), (width, height), opts.exr);
    let progress = frames_progress(frames, format!("{} {}", scene.name, mode.name()));
    let mut log = PerfLog::default();
    for i in 0..frames {
        let start = Instant::now();
        move_light(renderer, i)?;
        if i + 1 < frames {
            // Frames in flight: the next view's CPU work overlaps this frame.
            renderer.set_next_view(eye_of(i + 1), scene.orbit.view(eye_of(i + 1)));
        }
        let (stats, pixels) = source.frame_if(renderer, scene, eye_of(i), opts.capture)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        log.record(ms, &stats.passes, stats.cpu);
        if let Some(pixels) = pixels
            && !writer.send(i, pixels)
        {
            break; // the writer stopped: its error is reported below
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    writer.finish()?;
    // Decodes still running count too: they ran while frames rendered.
    renderer.settle();
    log.add_ahead_decodes(renderer.drain_ahead_decode_ms());
    let report = log.report(
        &device.name,
        &scene.name,
        &format!("{mode:?}"),
        [width, height],
        &renderer.setup_timings,
    );
    crate::util::files::write_json(&out.join("perf.json"), &report)?;
    let video = (opts.capture && opts.video)
        .then(|| path_video(&out, frames))
        .transpose()?;
    Ok(Played {
        report,
        video,
        out,
        frames,
    })
}

/// A progress bar over `frames` frames, labelled `message`.
fn frames_progress(frames: u32, message: String) -> indicatif::ProgressBar {
    let progress = indicatif::ProgressBar::new(u64::from(frames)).with_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    progress.set_message(message);
    progress
}

/// The mode `opts` asks for: as given, else static EM under a moving light,
/// else the scene's default; a moving light in another mode is an error.
fn play_mode(opts: &PlayOptions, scene: &Scene) -> Result<Mode> {
    let mode = match (opts.mode, opts.light_path) {
        (Some(mode), _) => mode,
        (None, Some(_)) => Mode::StaticEm,
        (None, None) => Mode::default_for(scene),
    };
    if opts.light_path.is_some() && mode != Mode::StaticEm {
        bail!(
            "--light-path with --mode {}: a moving light plays static-EM frames (the other \
             modes' maps hold the scene's own lights); use --mode static-em or leave --mode out",
            mode.name()
        );
    }
    Ok(mode)
}

/// `--light-path`: the relightable panorama (traced and projected once,
/// cached under `out/relight/`, stored through the codec) on the renderer,
/// k = 16; the path and where it turns around.
fn setup_light_path(
    scene: &Scene,
    out: &Path,
    lp: LightPathOptions,
    renderer: &mut Renderer,
) -> Result<(LightPath, glam::Vec3)> {
    let what = "--light-path-size, --light-path-grid, --light-path-spp";
    let grid = GridSettings::new(lp.size, lp.grid, lp.spp, 1, 0, what)?;
    let r = relightable(scene, &grid, out, true)?;
    let stored = compressed(&r.maps, &r.path, &r.key, DEFAULT_RATIO)?;
    renderer.set_light_path(scene, &stored.maps, &r.positions, LIGHT_PATH_K)?;
    Ok((lp.path, inference::relight::panorama_origin(scene)))
}

/// Where a run's frames come from: the rasteriser in some mode, or the
/// tracer (the gold standard, seconds per frame).
pub enum FrameSource<'s> {
    Raster(FrameMode),
    Trace(Box<Tracer<'s>>, TraceSettings),
}

impl FrameSource<'_> {
    /// One frame from `eye` (looking at the orbit centre), its pixels left
    /// where they are: a run that keeps no frames spends no CPU reading
    /// them back (4.9 MB converted from f16 at 640×480, on cores the next
    /// frame's work needs).
    pub fn draw(
        &mut self,
        renderer: &mut Renderer,
        scene: &Scene,
        eye: glam::Vec3,
    ) -> Result<FrameStats> {
        match self {
            FrameSource::Raster(mode) => Ok(renderer.frame(*mode, eye, scene.orbit.view(eye))?),
            FrameSource::Trace(..) => Ok(self.frame(renderer, scene, eye)?.0),
        }
    }

    /// [`FrameSource::draw`], and the frame as read back when it is kept
    /// (`keep`): a rasterised frame as half floats, which the writer
    /// converts on its own thread.
    pub fn frame_if(
        &mut self,
        renderer: &mut Renderer,
        scene: &Scene,
        eye: glam::Vec3,
        keep: bool,
    ) -> Result<(FrameStats, Option<Captured>)> {
        match (keep, &self) {
            (false, _) => Ok((self.draw(renderer, scene, eye)?, None)),
            (true, FrameSource::Raster(_)) => {
                let stats = self.draw(renderer, scene, eye)?;
                Ok((stats, Some(Captured::Halves(renderer.frame_halves()?))))
            }
            (true, FrameSource::Trace(..)) => {
                let (stats, pixels) = self.frame(renderer, scene, eye)?;
                Ok((stats, Some(Captured::Pixels(pixels))))
            }
        }
    }

    /// One frame from `eye` (looking at the orbit centre) and its pixels.
    pub fn frame(
        &mut self,
        renderer: &mut Renderer,
        scene: &Scene,
        eye: glam::Vec3,
    ) -> Result<(FrameStats, Vec<[f32; 4]>)> {
        match self {
            FrameSource::Raster(_) => {
                let stats = self.draw(renderer, scene, eye)?;
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
                let stats = FrameStats {
                    passes: Vec::new(),
                    cpu: Default::default(),
                };
                Ok((stats, pixels))
            }
        }
    }
}

/// The PEM settings of a PEM `mode` with `pem`'s knobs.
pub fn pem_settings(mode: Mode, pem: &PemOptions, scene: &Scene) -> Result<PemSettings> {
    let kind = match mode {
        Mode::LayeredPem => PemKind::Layered,
        Mode::SpherePem => PemKind::Sphere,
        Mode::Ptm => PemKind::Ptm,
        _ => bail!("internal: {mode:?} plays no PEMs"),
    };
    let mut settings = PemSettings::new(kind);
    settings.blend = pem.blend;
    settings.local_layer = pem.local_layer;
    settings.spacing = pem.spacing;
    settings.view_blend = pem.view_blend;
    settings.filtering = pem.filtering;
    settings.compositing = pem.compositing;
    settings.edge_filter = pem.edge_filter;
    if let Some(size) = pem.em_size {
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
    Ok(settings)
}
