//! Per-sample room-shell maps of the glass object (thesis §6.3.3): at
//! every `[objects.glass] shell_every`-th orbit line, the traced shell map
//! refined by the frame solve ([`solve`]) against the whole frame traced
//! from that sample and the views `view_spread_deg` above and below it.
//! Cached beside the traced map, one keyed file per line; playback blends
//! the two nearest (`glass::samples`).
//!
//! One solve's gain is local to its views (README, *Glass*: +0.5 dB on and
//! beside them, up to −1.9 dB 10° off with one view), hence one map per
//! sample rather than one for the orbit.

pub mod layered;
pub mod pack;
pub mod solve;
pub mod solve_layers;
pub mod views;

use crate::glass::samples::SampleShells;
use crate::probe::VulkanProbe;
use anyhow::{Context, Result};
use glam::Vec3;
use half::f16;
use inference::glass::{Lens, ShellSet};
use inference::key::{Freshness, Key};
use inference::scene::{GlassSettings, Scene};
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::trace::Tracer;
use std::path::{Path, PathBuf};
use std::time::Instant;
use views::ViewSettings;

/// Samples per pixel of each view's targets and frame (4 gained +0.51 dB
/// on the sample against +0.74 for 16, in 13 against 18 s a view).
pub const SHELL_VIEW_SPP: u32 = 16;
/// τ of the probe geometry: the eval's finest. A map solved through τ = 3
/// lookups still gains at τ = 5 and 10; one solved at 5 gains little at 3.
pub const SHELL_SOLVE_TAU: f32 = 3.0;
/// The prior on the correction to the traced map (λ‖δ‖²).
pub const SHELL_REFINE: f32 = 0.1;
/// Bumped when what a per-sample map holds changes.
const VERSION: u64 = 2;

/// The glass object the maps belong to, and its room shell.
pub struct GlassObject<'a> {
    pub scene: &'a Scene,
    pub index: u32,
    pub settings: GlassSettings,
    pub origin: Vec3,
    /// The traced shell map's key (the refined maps start from it).
    pub traced_key: Key,
}

impl<'a> GlassObject<'a> {
    /// The scene's glass object (the first, as playback's) when it asks
    /// for per-sample maps (`shell_every`); its shell map's origin and size
    /// are playback's (the mesh's centroid, `resolution`).
    pub fn for_scene(scene: &'a Scene) -> Option<GlassObject<'a>> {
        let (index, object, settings) = per_sample_object(scene)?;
        let origin = object.mesh.area_weighted_centroid();
        let traced_key = crate::glass::shell::shell_key(scene, index, origin, settings.resolution);
        Some(GlassObject {
            scene,
            index,
            settings,
            origin,
            traced_key,
        })
    }
}

/// The scene's glass object (the first, as playback's: its index, the
/// object, its settings) when it asks for per-sample maps (`shell_every`).
fn per_sample_object(scene: &Scene) -> Option<(u32, &inference::scene::Object, GlassSettings)> {
    let (index, object) = (scene.objects.iter().enumerate()).find(|(_, o)| o.glass.is_some())?;
    let settings = object.glass.clone()?;
    let lines = settings.shell_lines(scene.orbit.samples);
    (!lines.is_empty()).then_some((index as u32, object, settings))
}

/// Where line `line`'s map is cached under `out`.
pub fn sample_path(out: &Path, line: u32) -> PathBuf {
    crate::glass::shell::shell_path(out).with_file_name(format!("room_shell_line{line:04}.bin"))
}

/// What line `line`'s map depends on.
fn sample_key(g: &GlassObject, line: u32, size: (u32, u32)) -> Key {
    let az = g.scene.orbit.angle_deg(line);
    let key = g.traced_key.clone().with("sample shell", VERSION);
    views_key(
        key.with("azimuth", u64::from(az.to_bits())),
        &g.settings,
        size,
    )
}

/// `key` with what a sample's views and solve depend on: their elevations,
/// the frame size, spp, τ and the prior.
fn views_key(mut key: Key, settings: &GlassSettings, size: (u32, u32)) -> Key {
    for e in settings.view_elevations() {
        key = key.with("view elevation", u64::from(e.to_bits()));
    }
    key.with("width", u64::from(size.0))
        .with("height", u64::from(size.1))
        .with("spp", u64::from(SHELL_VIEW_SPP))
        .with("tau", u64::from(SHELL_SOLVE_TAU.to_bits()))
        .with("refine", u64::from(SHELL_REFINE.to_bits()))
}

/// The per-sample maps of `g` at frame `size`, from `traced` (the traced
/// map's f16 RGBA bytes): read where fresh, else solved on `device` and
/// written.
pub fn sample_shells(
    g: &GlassObject,
    out: &Path,
    device: &crate::backend::DeviceOptions,
    size: (u32, u32),
    traced: &[u8],
) -> Result<SampleShells> {
    let lines = g.settings.shell_lines(g.scene.orbit.samples);
    let mut maps: Vec<Option<Vec<u8>>> = lines
        .iter()
        .map(|&line| read_fresh(&sample_path(out, line), &sample_key(g, line, size)))
        .collect();
    let todo: Vec<usize> = (0..lines.len()).filter(|&i| maps[i].is_none()).collect();
    for &i in &todo {
        crate::util::files::check_overwrite_keyed(&sample_path(out, lines[i]))?;
    }
    if !todo.is_empty() {
        let mut solver = Solver::new(g, device, size, traced)?;
        let bar = progress(todo.len());
        for &i in &todo {
            let line = lines[i];
            bar.set_message(format!("line {line}"));
            let bytes = solver.solve(line)?;
            let file = sample_path(out, line);
            inference::files::write_bytes(&file, &bytes)?;
            inference::key::write_record(&file, &sample_key(g, line, size))?;
            maps[i] = Some(bytes);
            bar.inc(1);
        }
        bar.finish_and_clear();
        eprintln!(
            "solved {} per-sample shell maps in {:.1} s ({} views each): {}",
            todo.len(),
            solver.start.elapsed().as_secs_f64(),
            g.settings.view_elevations().len(),
            sample_path(out, lines[todo[0]]).display()
        );
    }
    Ok(SampleShells {
        azimuths: azimuths(g),
        maps: maps.into_iter().flatten().collect(),
    })
}

/// The azimuths of `g`'s per-sample maps.
fn azimuths(g: &GlassObject) -> Vec<f32> {
    (g.settings.shell_lines(g.scene.orbit.samples).iter())
        .map(|&l| g.scene.orbit.angle_deg(l))
        .collect()
}

/// The key of the container of `g`'s per-sample maps at frame `size`.
fn packed_key(g: &GlassObject, size: (u32, u32)) -> Key {
    let lines = g.settings.shell_lines(g.scene.orbit.samples);
    let keys: Vec<Key> = lines.iter().map(|&l| sample_key(g, l, size)).collect();
    pack::container_key(&keys)
}

/// `shells` compressed by the codec ([`pack`]) and written under `key`;
/// decoded, with the container's bytes.
fn pack_shells(
    shells: SampleShells,
    key: &Key,
    out: &Path,
    size: u32,
) -> Result<(SampleShells, u64)> {
    let file = pack::container_path(out);
    crate::util::files::check_overwrite_keyed(&file)?;
    let start = Instant::now();
    let bytes = pack::encode(&shells, size, pack::SHELL_RATIO)?;
    inference::files::write_bytes(&file, &bytes)?;
    inference::key::write_record(&file, key)?;
    eprintln!(
        "compressed {} per-sample shell maps {:.0}:1 in {:.1} s: {} ({} bytes)",
        shells.maps.len(),
        pack::SHELL_RATIO,
        start.elapsed().as_secs_f64(),
        file.display(),
        bytes.len()
    );
    let len = bytes.len() as u64;
    Ok((pack::decode(bytes, shells.azimuths, &file)?, len))
}

/// The bytes of `file` when its record says `key` and it reads whole.
fn read_fresh(file: &Path, key: &Key) -> Option<Vec<u8>> {
    match inference::key::freshness(file, key) {
        Freshness::Fresh => match inference::key::read_verified(file) {
            Ok(bytes) => Some(bytes),
            Err(why) => {
                eprintln!("{why}: solving it again");
                None
            }
        },
        _ => None,
    }
}

fn progress(len: usize) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(len as u64).with_style(
        indicatif::ProgressStyle::with_template(
            "glass shells [{bar:30}] {pos}/{len} samples {elapsed}, about {eta} left: {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    )
}

/// What every line's solve shares: the tracer, the probe, the lens.
struct Solver<'a> {
    g: &'a GlassObject<'a>,
    tracer: Tracer<'a>,
    probe: VulkanProbe,
    lens: Lens,
    shells: ShellSet,
    traced: Vec<Vec<f32>>,
    size: (u32, u32),
    start: Instant,
}

impl<'a> Solver<'a> {
    fn new(
        g: &'a GlassObject<'a>,
        device: &crate::backend::DeviceOptions,
        size: (u32, u32),
        traced: &[u8],
    ) -> Result<Self> {
        let start = Instant::now();
        let object = &g.scene.objects[g.index as usize];
        let traced = channels_of(traced, 3)
            .map_err(|e| anyhow::anyhow!("the traced shell map's bytes: {e}"))?;
        let device = crate::backend::create_device(device)?;
        Ok(Self {
            g,
            tracer: Tracer::new(g.scene)?,
            probe: VulkanProbe::new(&device)?,
            lens: Lens::new(g.scene, &object.name)?,
            shells: inference::glass::room_shell(
                g.scene,
                g.origin,
                inference::glass::room_box_shape(g.scene),
            ),
            traced,
            size,
            start,
        })
    }

    /// Line `line`'s refined map as f16 RGBA bytes (negative texels clamped).
    fn solve(&mut self, line: u32) -> Result<Vec<u8>> {
        let orbit = &self.g.scene.orbit;
        let az = orbit.angle_deg(line);
        let settings = ViewSettings {
            size: self.size,
            spp: SHELL_VIEW_SPP,
            tau: SHELL_SOLVE_TAU,
        };
        let views = (self.g.settings.view_elevations().iter().enumerate())
            .map(|(i, &el)| {
                let key =
                    ((u64::from(line) << 8) | (2 * i as u64)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                views::frame_view(
                    &self.tracer,
                    &self.lens,
                    &self.shells,
                    orbit.eye(az, el),
                    settings,
                    key,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let shape = TextureShape::Cube {
            size: self.g.settings.resolution,
        };
        let (map, _) = solve::solve_frames(
            &mut self.probe,
            &views,
            shape,
            &self.traced,
            Some(SHELL_REFINE),
        )
        .with_context(|| format!("solving the shell map of orbit line {line}"))?;
        let len = TextureLayout::full_chain(shape).len();
        Ok(rgba_bytes(&map, len))
    }
}

/// The first `channels` channels of f16 RGBA texel bytes, each as f32 in
/// texel order (what a solve starts from).
fn channels_of(bytes: &[u8], channels: usize) -> Result<Vec<Vec<f32>>, bytemuck::PodCastError> {
    let halves: &[f16] = bytemuck::try_cast_slice(bytes)?;
    Ok((0..channels)
        .map(|c| halves.chunks_exact(4).map(|t| t[c].to_f32()).collect())
        .collect())
}

/// A solved map (3 or 4 channels of `len` texels) as f16 RGBA bytes:
/// colours ≥ 0, alpha clamped to [0, 1], 1 where the map has none.
fn rgba_bytes(map: &[Vec<f32>], len: usize) -> Vec<u8> {
    let at = |c: usize, i: usize| map.get(c).and_then(|m| m.get(i)).copied();
    let halves: Vec<f16> = (0..len)
        .flat_map(|i| {
            let rgb = |c: usize| at(c, i).unwrap_or(0.0).max(0.0);
            let alpha = at(3, i).map_or(1.0, |a| a.clamp(0.0, 1.0));
            [rgb(0), rgb(1), rgb(2), alpha].map(f16::from_f32)
        })
        .collect();
    bytemuck::cast_slice(&halves).to_vec()
}

/// The key the per-sample maps' container of `scene` carries at frame
/// `size`; None when the scene asks for no per-sample maps.
pub fn expected_key(scene: &Scene, size: (u32, u32)) -> Option<Key> {
    GlassObject::for_scene(scene).map(|g| packed_key(&g, size))
}

/// The fresh container of `ctx` (under `--out`, then the shipped one, read
/// only) with its path and bytes; None when neither matches `key`.
fn fresh_container(ctx: &super::CompileContext, key: &Key) -> Option<(PathBuf, Vec<u8>)> {
    let mut dirs = vec![ctx.out.to_path_buf()];
    dirs.extend(ctx.shipped.clone());
    dirs.into_iter().find_map(|dir| {
        let file = pack::container_path(&dir);
        read_fresh(&file, key).map(|bytes| (file, bytes))
    })
}

/// The per-sample maps of `g` solved where missing under `ctx.out` and
/// compressed: decoded, with the container's bytes (`raw`: as solved).
fn compile_shells(
    ctx: &super::CompileContext,
    g: &GlassObject,
    key: &Key,
    raw: bool,
) -> Result<(SampleShells, u64)> {
    let size = g.settings.resolution;
    let traced =
        crate::glass::shell::room_shell_bytes(ctx.scene, ctx.out, g.index, g.origin, size)?;
    let shells = sample_shells(g, ctx.out, ctx.device, ctx.size, &traced)?;
    match raw {
        true => {
            let bytes = shells.maps.iter().map(|m| m.len() as u64).sum();
            Ok((shells, bytes))
        }
        false => pack_shells(shells, key, ctx.out, size),
    }
}

/// `engine compile` of a glass scene: its per-sample maps' container under
/// `ctx.out` (solved where missing); None when the scene asks for none.
pub fn compile(ctx: &super::CompileContext) -> Result<Option<(PathBuf, u64)>> {
    // Layered shells: every layer's maps (the room shell's alone would
    // not be played).
    if let Some(done) = layered::compile(ctx)? {
        return Ok(Some(done));
    }
    let Some(g) = GlassObject::for_scene(ctx.scene) else {
        return Ok(None);
    };
    let key = packed_key(&g, ctx.size);
    let file = pack::container_path(ctx.out);
    if let Some(bytes) = read_fresh(&file, &key) {
        return Ok(Some((file, bytes.len() as u64)));
    }
    let (_, bytes) = compile_shells(ctx, &g, &key, false)?;
    Ok(Some((file, bytes)))
}

/// Loads the per-sample shell maps of the scene's glass object into
/// `renderer`, when the scene asks for them: from a fresh container (under
/// `--out`, or the one shipped in `assets/compiled/`), else solved where
/// missing and compressed; with `raw` as solved.
pub fn load(
    ctx: &super::CompileContext,
    renderer: &mut crate::renderer::Renderer,
    raw: bool,
) -> Result<()> {
    let Some(g) = GlassObject::for_scene(ctx.scene) else {
        return Ok(());
    };
    if renderer.glass.is_none() {
        return Ok(());
    }
    let key = packed_key(&g, ctx.size);
    // A fresh container plays without the maps it was made from.
    let cached = match raw {
        true => None,
        false => fresh_container(ctx, &key),
    };
    let (shells, bytes) = match cached {
        Some((file, bytes)) => {
            if !file.starts_with(ctx.out) {
                eprintln!(
                    "{}: playing the shipped per-sample shell maps {} (its key matches; \
                     --recompile solves them here)",
                    ctx.scene.name,
                    file.display()
                );
            }
            let len = bytes.len() as u64;
            (pack::decode(bytes, azimuths(&g), &file)?, len)
        }
        None => compile_shells(ctx, &g, &key, raw)?,
    };
    renderer.load_glass_samples(&shells)?;
    renderer.map_bytes = Some(bytes);
    eprintln!(
        "hybrid glass blends {} per-sample shell maps (every {} orbit lines; --traced-shell: the one traced map)",
        shells.maps.len(),
        g.settings.shell_every
    );
    Ok(())
}
