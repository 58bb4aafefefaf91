//! Per-sample maps of layered shells (thesis §6.3.3 over §6.3's layers):
//! where objects stand near the glass and the scene asks for per-sample
//! maps (`[objects.glass] shell_every`), every layer of every sample is
//! solved from the views of that sample ([`super::solve_layers`]),
//! starting from the layer's traced map; cached one keyed file per line
//! and layer, compressed into one container (inner layers RGBA, the
//! outermost RGB) and blended by azimuth in playback, layer by layer.

use super::solve_layers::{solve_layer, solve_outer};
use super::views::{LayerView, ViewSettings, layer_view};
use super::{
    SHELL_REFINE, SHELL_SOLVE_TAU, SHELL_VIEW_SPP, channels_of, pack, progress, read_fresh,
    rgba_bytes, views_key,
};
use crate::glass::samples::LayerSamples;
use crate::probe::VulkanProbe;
use anyhow::{Context, Result};
use inference::glass::{Lens, ShellSet};
use inference::key::Key;
use inference::scene::{GlassSettings, Scene};
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::trace::Tracer;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Bumped when what a per-sample layer map holds changes.
const VERSION: u64 = 1;
/// Bumped when the outermost layer's solve changes (2: fitted to the
/// whole frame, not to its own images).
const OUTER_VERSION: u64 = 2;

/// A glass object whose shells are layered and that asks for per-sample
/// maps.
pub struct LayeredObject<'a> {
    pub scene: &'a Scene,
    pub index: u32,
    pub settings: GlassSettings,
    pub set: ShellSet,
}

impl<'a> LayeredObject<'a> {
    /// The scene's glass object (the first, as playback's) when it asks
    /// for per-sample maps and its placed shells (cached under `out`) are
    /// more than the room's one.
    pub fn for_scene(scene: &'a Scene, out: &Path) -> Result<Option<LayeredObject<'a>>> {
        let Some((index, object, settings)) = super::per_sample_object(scene) else {
            return Ok(None);
        };
        let lens = Lens::new(scene, &object.name)?;
        let (set, _) = crate::glass::layers::placed_shells(scene, out, &lens, settings.shells)?;
        Ok((set.shells.len() >= 2).then_some(LayeredObject {
            scene,
            index,
            settings,
            set,
        }))
    }

    fn lines(&self) -> Vec<u32> {
        self.settings.shell_lines(self.scene.orbit.samples)
    }

    fn azimuths(&self) -> Vec<f32> {
        let orbit = &self.scene.orbit;
        self.lines().iter().map(|&l| orbit.angle_deg(l)).collect()
    }

    /// What layer `k`'s map of line `line` depends on.
    fn sample_key(&self, line: u32, k: usize, size: (u32, u32)) -> Key {
        let (scene, res) = (self.scene, self.settings.resolution);
        let traced = crate::glass::layers::layer_key(scene, self.index, &self.set, k, res);
        let az = scene.orbit.angle_deg(line);
        let mut key =
            (traced.with("layered sample shell", VERSION)).with("azimuth", u64::from(az.to_bits()));
        if k + 1 == self.set.shells.len() {
            key = key.with("outermost", OUTER_VERSION);
        }
        views_key(key, &self.settings, size)
    }

    /// The key of the container of every line's layers at frame `size`.
    fn packed_key(&self, size: (u32, u32)) -> Key {
        let n = self.set.shells.len();
        let keys: Vec<Key> = (self.lines().iter())
            .flat_map(|&l| (0..n).map(move |k| (l, k)))
            .map(|(l, k)| self.sample_key(l, k, size))
            .collect();
        pack::container_key(&keys).with("layers", n as u64)
    }
}

/// Where layer `k`'s map of line `line` is cached under `out`.
pub fn sample_path(out: &Path, line: u32, k: usize) -> PathBuf {
    crate::glass::layers::layer_path(out, k).with_file_name(format!("layer_{k}_line{line:04}.bin"))
}

/// The maps of `g` at frame `size`: read where fresh, else solved on
/// `device` from `traced` (each layer's traced map) and written.
fn sample_layers(
    g: &LayeredObject,
    out: &Path,
    device: &crate::backend::DeviceOptions,
    size: (u32, u32),
    traced: &[Vec<u8>],
) -> Result<LayerSamples> {
    let (lines, n) = (g.lines(), g.set.shells.len());
    let read = |l: u32, k: usize| read_fresh(&sample_path(out, l, k), &g.sample_key(l, k, size));
    let mut maps: Vec<Vec<Option<Vec<u8>>>> = (lines.iter())
        .map(|&l| (0..n).map(|k| read(l, k)).collect())
        .collect();
    let todo: Vec<usize> = (0..lines.len())
        .filter(|&i| maps[i].iter().any(Option::is_none))
        .collect();
    for &i in &todo {
        for k in 0..n {
            crate::util::files::check_overwrite_keyed(&sample_path(out, lines[i], k))?;
        }
    }
    if let Some(&first) = todo.first() {
        let (start, mut solved) = (Instant::now(), 0);
        let mut solver = Solver::new(g, out, device, size, traced)?;
        let bar = progress(todo.len());
        for &i in &todo {
            let line = lines[i];
            bar.set_message(format!("line {line}, {n} layers"));
            let missing: Vec<usize> = (0..n).filter(|&k| maps[i][k].is_none()).collect();
            solved += missing.len();
            for (k, bytes) in solver.solve(line, &missing)? {
                let file = sample_path(out, line, k);
                inference::files::write_bytes(&file, &bytes)?;
                inference::key::write_record(&file, &g.sample_key(line, k, size))?;
                maps[i][k] = Some(bytes);
            }
            bar.inc(1);
        }
        bar.finish_and_clear();
        eprintln!(
            "solved per-sample shell layer maps: {solved} of {} ({} orbit lines) in {:.1} s ({} views each): {}",
            n * lines.len(),
            todo.len(),
            start.elapsed().as_secs_f64(),
            g.settings.view_elevations().len(),
            sample_path(out, lines[first], 0).display()
        );
    }
    let mut layers = vec![Vec::with_capacity(lines.len()); n];
    for line in maps {
        for (k, map) in line.into_iter().enumerate() {
            layers[k].push(map.context("internal: a layer map neither read nor solved")?);
        }
    }
    Ok(LayerSamples {
        azimuths: g.azimuths(),
        layers,
    })
}

/// What every line's solve shares.
struct Solver<'a> {
    g: &'a LayeredObject<'a>,
    tracer: Tracer<'a>,
    probe: VulkanProbe,
    lens: Lens,
    /// Per layer, the traced map per channel (RGBA inner, RGB outermost).
    traced: Vec<Vec<Vec<f32>>>,
    size: (u32, u32),
}

impl<'a> Solver<'a> {
    fn new(
        g: &'a LayeredObject<'a>,
        out: &Path,
        device: &crate::backend::DeviceOptions,
        size: (u32, u32),
        traced: &[Vec<u8>],
    ) -> Result<Self> {
        let object = &g.scene.objects[g.index as usize];
        let n = g.set.shells.len();
        let traced = (traced.iter().enumerate())
            .map(|(k, bytes)| {
                channels_of(bytes, if k + 1 < n { 4 } else { 3 }).map_err(|e| {
                    let file = crate::glass::layers::layer_path(out, k);
                    anyhow::anyhow!("shell layer {k}'s traced map {}: {e}", file.display())
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let device = crate::backend::create_device(device)?;
        Ok(Self {
            g,
            tracer: Tracer::new(g.scene)?,
            probe: VulkanProbe::new(&device)?,
            lens: Lens::new(g.scene, &object.name)?,
            traced,
            size,
        })
    }

    /// Layers `layers`' maps of line `line` as f16 RGBA bytes: colours
    /// ≥ 0, alpha within [0, 1] (1 on the outermost).
    fn solve(&mut self, line: u32, layers: &[usize]) -> Result<Vec<(usize, Vec<u8>)>> {
        let orbit = &self.g.scene.orbit;
        let az = orbit.angle_deg(line);
        let settings = ViewSettings {
            size: self.size,
            spp: SHELL_VIEW_SPP,
            tau: SHELL_SOLVE_TAU,
        };
        let views: Vec<LayerView> = (self.g.settings.view_elevations().iter().enumerate())
            .map(|(v, &el)| {
                let key = move |i: u64| {
                    ((u64::from(line) << 16) | ((v as u64) << 8) | i)
                        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
                };
                layer_view(
                    &self.tracer,
                    &self.lens,
                    &self.g.set,
                    orbit.eye(az, el),
                    settings,
                    key,
                )
            })
            .collect::<Result<_>>()?;
        let shape = TextureShape::Cube {
            size: self.g.settings.resolution,
        };
        let len = TextureLayout::full_chain(shape).len();
        let outer = self.traced.len() - 1;
        (layers.iter())
            .map(|&k| {
                let traced = self.traced.get(k).context("no such layer")?;
                let map = match k == outer {
                    true => solve_outer(&mut self.probe, &views, shape, traced, SHELL_REFINE),
                    false => solve_layer(&mut self.probe, &views, k, shape, traced, SHELL_REFINE),
                };
                let map = map.with_context(|| format!("orbit line {line}"))?;
                Ok((k, rgba_bytes(&map, len)))
            })
            .collect()
    }
}

/// The per-sample layer maps of `g` solved where missing under `ctx.out`
/// and compressed: decoded, with the container's bytes (`raw`: as solved).
fn compile_layers(
    ctx: &crate::compile::CompileContext,
    g: &LayeredObject,
    raw: bool,
) -> Result<(LayerSamples, u64)> {
    let res = g.settings.resolution;
    let traced = crate::glass::layers::layer_maps(ctx.scene, ctx.out, g.index, &g.set, res)?;
    let samples = sample_layers(g, ctx.out, ctx.device, ctx.size, &traced)?;
    if raw {
        let bytes = samples
            .layers
            .iter()
            .flatten()
            .map(|m| m.len() as u64)
            .sum();
        return Ok((samples, bytes));
    }
    let file = pack::layers_container_path(ctx.out);
    crate::util::files::check_overwrite_keyed(&file)?;
    let start = Instant::now();
    let bytes = pack::encode_layers(&samples.layers, res, pack::SHELL_RATIO)?;
    inference::files::write_bytes(&file, &bytes)?;
    inference::key::write_record(&file, &g.packed_key(ctx.size))?;
    eprintln!(
        "compressed {} layers of {} per-sample shell maps {:.0}:1 in {:.1} s: {} ({} bytes)",
        samples.layers.len(),
        samples.azimuths.len(),
        pack::SHELL_RATIO,
        start.elapsed().as_secs_f64(),
        file.display(),
        bytes.len()
    );
    let len = bytes.len() as u64;
    let n = samples.layers.len();
    let layers = pack::decode_layers(bytes, samples.azimuths.len(), n, &file)?;
    Ok((
        LayerSamples {
            azimuths: samples.azimuths,
            layers,
        },
        len,
    ))
}

/// `engine compile` of a layered glass scene: its per-sample layer maps'
/// container under `ctx.out` (solved where missing); None when the scene
/// is not layered or asks for no per-sample maps.
pub fn compile(ctx: &crate::compile::CompileContext) -> Result<Option<(PathBuf, u64)>> {
    let Some(g) = LayeredObject::for_scene(ctx.scene, ctx.out)? else {
        return Ok(None);
    };
    let file = pack::layers_container_path(ctx.out);
    if let Some(bytes) = read_fresh(&file, &g.packed_key(ctx.size)) {
        return Ok(Some((file, bytes.len() as u64)));
    }
    let (_, bytes) = compile_layers(ctx, &g, false)?;
    Ok(Some((file, bytes)))
}

/// Has `renderer`'s hybrid frames blend per-sample layer maps, when the
/// scene's shells are layered and it asks for them: from a fresh container
/// under `--out`, else solved where missing and compressed (`raw`: as
/// solved). Returns whether it did.
pub fn load(
    ctx: &crate::compile::CompileContext,
    renderer: &mut crate::renderer::Renderer,
    raw: bool,
) -> Result<bool> {
    if renderer.glass.is_none() {
        return Ok(false);
    }
    let Some(g) = LayeredObject::for_scene(ctx.scene, ctx.out)? else {
        return Ok(false);
    };
    let file = pack::layers_container_path(ctx.out);
    let n = g.set.shells.len();
    let fresh = (!raw)
        .then(|| read_fresh(&file, &g.packed_key(ctx.size)))
        .flatten();
    let (samples, bytes) = match fresh {
        Some(bytes) => {
            let len = bytes.len() as u64;
            let layers = pack::decode_layers(bytes, g.lines().len(), n, &file)?;
            let azimuths = g.azimuths();
            (LayerSamples { azimuths, layers }, len)
        }
        None => compile_layers(ctx, &g, raw)?,
    };
    renderer
        .load_glass_layer_samples(&samples, &g.set)
        .with_context(|| format!("playing the per-sample layer maps of {}", file.display()))?;
    renderer.map_bytes = Some(bytes);
    eprintln!(
        "hybrid glass blends {} per-sample maps of each of its {n} shell layers (every {} orbit lines)",
        samples.azimuths.len(),
        g.settings.shell_every
    );
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use half::f16;

    #[test]
    fn solved_maps_keep_colours_and_coverage_in_range() {
        let rgba = vec![
            vec![-1.0, 0.5],
            vec![2.0, 0.25],
            vec![0.0, 1.0],
            vec![1.5, -0.2],
        ];
        let halves: Vec<f16> = bytemuck::pod_collect_to_vec(&rgba_bytes(&rgba, 2));
        let got: Vec<f32> = halves.iter().map(|h| h.to_f32()).collect();
        assert_eq!(got, vec![0.0, 2.0, 0.0, 1.0, 0.5, 0.25, 1.0, 0.0]);
        // The outermost layer has no alpha: opaque.
        let rgb = &rgba[..3];
        let halves: Vec<f16> = bytemuck::pod_collect_to_vec(&rgba_bytes(rgb, 2));
        assert_eq!(halves[3].to_f32(), 1.0);
        assert_eq!(halves[7].to_f32(), 1.0);
    }
}
