//! PEM playback: per frame, texgen for every reflector, the samples the
//! eye needs made resident (decoded ahead on the worker, or now), and the
//! passes that draw them — deferred (G-buffer, then one compositing pass
//! shading each covered pixel once) or the papers' multipass — only what
//! the scene and the eye need: no local layer on convex-hull triangles, one
//! sample exactly on a grid line.

use super::ahead::{TexgenFrame, TexgenInputs, TexgenRequest};
use super::frame_sets::FrameSets;
use super::prefetch::{MapKey, Prefetcher, decode_into};
use super::reflector::PemReflector;
use super::residency::SLOTS;
use super::samples::{SampleBlend, ViewGrid};
pub use super::settings::{Compositing, PemKind, PemSettings};
use super::source::{MapLayer, MapSource};
use super::staging::StagingPool;
use crate::backend::upload::level_regions;
use crate::backend::{Buffer, Device, GpuError, GpuResult, Image, ImageDesc};
use crate::gpu_scene::GpuScene;
use crate::graph::Executor;
use crate::maps::ptm_edge;
use crate::passes::pem_deferred::GBuffer;
use crate::passes::target::{AroundRoom, Target};
use crate::passes::upload::{Upload, UploadPass};
use anyhow::{Result, bail};
use ash::vk;
use glam::{Mat4, Vec3};
use inference::scene::{Material, Orbit, Scene};
use std::time::Instant;

/// A map read into staging this frame, waiting for its upload pass.
struct Pending {
    class: usize,
    layer: usize,
    element: u32,
    buffer: Buffer,
}

/// CPU costs of preparing one PEM frame, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct PemCpu {
    pub texgen_ms: f64,
    /// Decoding on the frame (maps not decoded ahead).
    pub decode_ms: f64,
    pub decoded_maps: u32,
    /// Maps the worker had decoded ahead, straight into staging.
    pub prefetched_maps: u32,
    /// Waiting for the worker to finish a map it was decoding.
    pub prefetch_wait_ms: f64,
    /// Reflectors whose texgen and bands were computed ahead, during the
    /// previous frame ([`super::ahead`]).
    pub texgen_ahead: u32,
}

pub struct PemPlayer {
    pub(super) device: Device,
    pub settings: PemSettings,
    pub(super) sets: FrameSets,
    pub(super) reflectors: Vec<PemReflector>,
    pool: StagingPool,
    pending: Vec<Pending>,
    source: MapSource,
    prefetch: Option<Prefetcher>,
    grid: ViewGrid,
    orbit: Orbit,
    last_angles: Option<(f32, f32)>,
    frame: u64,
}

impl PemPlayer {
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        scene: &Scene,
        settings: PemSettings,
        source: MapSource,
        gbuffer: &GBuffer,
        formats: (vk::Format, vk::Format),
    ) -> Result<Self> {
        let layers = settings.layers();
        let mut reflectors = Vec::new();
        for (index, o) in scene.objects.iter().enumerate() {
            let f0 = match scene.materials.get(o.material) {
                Some(Material::Mirror { f0 }) | Some(Material::Glossy { f0, .. }) => *f0,
                _ => continue,
            };
            if o.em.is_none() {
                continue;
            }
            if let Some(layer) = layers.iter().find(|&&l| !source.has(&o.name, l)) {
                bail!(
                    "no {}.{} maps to play (run `engine infer --scene {} --all{}`)",
                    o.name,
                    layer.file_part(),
                    scene.arg(),
                    if *layer == MapLayer::Sphere {
                        " --sphere"
                    } else {
                        ""
                    }
                );
            }
            reflectors.push(PemReflector::new(device, scene, (index, o), f0, &settings)?);
        }
        let resolutions = assign_classes(&mut reflectors)?;
        let classes = resolutions
            .iter()
            .map(|&(resolution, members)| {
                let arrays = layers
                    .iter()
                    .map(|&l| map_array(device, l, (resolution, settings.drop_levels), members))
                    .collect::<Result<Vec<_>>>()?;
                Ok((resolution, arrays))
            })
            .collect::<Result<Vec<_>>>()?;
        let sets = FrameSets::new(device, executor, &settings, classes, gbuffer, formats)?;
        let leaf_bytes = layers
            .iter()
            .flat_map(|l| resolutions.iter().map(|&(r, _)| l.layout(r).len() * 8))
            .max()
            .unwrap_or(0);
        Ok(Self {
            device: device.clone(),
            settings,
            sets,
            reflectors,
            pool: StagingPool::new(device, leaf_bytes as u64),
            pending: Vec::new(),
            // Without a second handle playback still works, decoding in line.
            prefetch: source.reopen().ok().map(Prefetcher::new),
            source,
            grid: ViewGrid::from_orbit(&scene.orbit),
            orbit: scene.orbit.clone(),
            last_angles: None,
            frame: 0,
        })
    }

    /// Forgets every image's tracked state before they are destroyed.
    pub fn release(&self, executor: &mut Executor) {
        self.sets.release(executor);
    }

    /// Blends between these azimuth lines only (`None`: every line).
    pub fn use_azimuth_lines(&mut self, lines: Option<&[u32]>) {
        self.grid = std::mem::take(&mut self.grid).with_azimuths_used(lines);
    }

    /// Blends between these elevation rings only (`None`: every ring).
    pub fn use_rings(&mut self, rings: Option<&[u32]>) {
        self.grid = std::mem::take(&mut self.grid).with_elevations_used(rings);
    }

    /// The samples a frame from `eye` draws.
    pub fn blend(&self, eye: Vec3) -> SampleBlend {
        let s = &self.settings;
        super::samples::sample_blend(
            &self.grid,
            &self.orbit,
            eye,
            s.spacing,
            s.blend,
            s.view_blend,
        )
    }

    /// CPU work before recording a frame: texgen for `eye`, and the maps of
    /// `blend`'s samples that are not resident into staging. The previous
    /// frame's uploads have run (its fence was waited on), so their
    /// staging buffers go back to the pool first. `next_eye`, when the
    /// caller knows it, is where the next frame looks from: its samples
    /// are decoded ahead first.
    pub fn prepare(
        &mut self,
        eye: Vec3,
        view: (glam::Mat4, (u32, u32)),
        blend: &SampleBlend,
        next_eye: Option<Vec3>,
    ) -> Result<PemCpu> {
        self.frame += 1;
        for p in self.pending.drain(..) {
            self.pool.give(p.buffer);
        }
        if let Some(prefetch) = self.prefetch.as_mut() {
            prefetch
                .reclaim()
                .into_iter()
                .for_each(|b| self.pool.give(b));
        }
        let mut cpu = PemCpu::default();
        let needed: Vec<u32> = blend.indices().collect();
        for ri in 0..self.reflectors.len() {
            let start = Instant::now();
            let request = self.texgen_request(eye, view);
            if self.reflectors[ri].texgen(request)? {
                cpu.texgen_ahead += 1;
            }
            cpu.texgen_ms += start.elapsed().as_secs_f64() * 1e3;
            let Some(fills) = self.reflectors[ri].table.assign(&needed, self.frame) else {
                bail!(
                    "internal: {} samples do not fit {SLOTS} slots",
                    needed.len()
                );
            };
            for (sample, slot) in fills {
                self.fill_slot(ri, slot, sample, &mut cpu)?;
            }
        }
        if let Some(edges) = self.sets.edges.as_mut() {
            let outline: Vec<vk::Rect2D> = self
                .reflectors
                .iter()
                .flat_map(|r| r.outline().iter().copied())
                .collect();
            edges.set_outline(&outline)?;
        }
        if let Some(next) = next_eye {
            self.prefetch_blend(&self.blend(next));
        }
        self.prefetch_next(eye);
        Ok(cpu)
    }

    /// The next frame's texgen work (one job per reflector), for a worker
    /// to run while this frame renders ([`super::ahead`]).
    pub fn ahead_jobs(
        &self,
        eye: Vec3,
        view: (glam::Mat4, (u32, u32)),
    ) -> Vec<(TexgenInputs<'_>, TexgenRequest)> {
        let request = self.texgen_request(eye, view);
        self.reflectors
            .iter()
            .map(|r| (r.inputs(), request))
            .collect()
    }

    /// What the texgen of a frame from `eye` through `view` (view-projection,
    /// size) depends on.
    fn texgen_request(
        &self,
        eye: Vec3,
        (view_proj, size): (glam::Mat4, (u32, u32)),
    ) -> TexgenRequest {
        TexgenRequest {
            eye,
            view_proj,
            size,
            settings: self.settings,
        }
    }

    /// Hands each reflector what [`Self::ahead_jobs`]' worker computed.
    pub fn set_ahead(&mut self, frames: Vec<TexgenFrame>) {
        for (r, frame) in self.reflectors.iter_mut().zip(frames) {
            r.set_ahead(frame);
        }
    }

    /// Every layer of `sample` into staging for slot `slot` of reflector `ri`.
    fn fill_slot(&mut self, ri: usize, slot: usize, sample: u32, cpu: &mut PemCpu) -> Result<()> {
        let r = &self.reflectors[ri];
        for (layer_index, &layer) in self.settings.layers().iter().enumerate() {
            let key = MapKey {
                object: r.name.clone(),
                layer,
                resolution: r.resolution,
                sample,
            };
            let start = Instant::now();
            let taken = self.prefetch.as_mut().and_then(|p| p.take(&key));
            // Counted whether the worker's decode succeeded or not.
            cpu.prefetch_wait_ms += start.elapsed().as_secs_f64() * 1e3;
            let buffer = match taken {
                Some((buffer, _)) => {
                    cpu.prefetched_maps += 1;
                    buffer
                }
                None => {
                    let start = Instant::now();
                    let mut buffer = self.pool.take()?;
                    decode_into(&mut self.source, &key, &mut buffer)?;
                    cpu.decode_ms += start.elapsed().as_secs_f64() * 1e3;
                    buffer
                }
            };
            cpu.decoded_maps += 1;
            self.pending.push(Pending {
                class: r.class,
                layer: layer_index,
                element: r.base + slot as u32,
                buffer,
            });
        }
        Ok(())
    }

    /// Asks the worker for the samples of the next cell in the direction
    /// the eye moves, for every reflector that does not hold them yet.
    fn prefetch_next(&mut self, eye: Vec3) {
        let (az, el) = self.orbit.angles(eye);
        let last = self.last_angles.replace((az, el));
        let Some((last_az, last_el)) = last else {
            return;
        };
        let (da, de) = (az - last_az, el - last_el);
        if da == 0.0 && de == 0.0 {
            return;
        }
        let s = &self.settings;
        let (cell_a, cell_e) = self.grid.cell_size(az, el, s.spacing);
        let ahead = self.grid.blend_by(
            az + da.signum() * cell_a * f32::from(da != 0.0),
            el + de.signum() * cell_e * f32::from(de != 0.0),
            s.spacing,
            s.blend,
            s.view_blend,
        );
        self.prefetch_blend(&ahead);
    }

    /// Asks the worker for `blend`'s samples, every layer, for every
    /// reflector that does not hold them and has not asked yet.
    fn prefetch_blend(&mut self, blend: &SampleBlend) {
        let Some(prefetch) = self.prefetch.as_mut() else {
            return;
        };
        for r in &self.reflectors {
            for sample in blend.indices().filter(|&k| !r.table.holds(k)) {
                for layer in self.settings.layers() {
                    let key = MapKey {
                        object: r.name.clone(),
                        layer,
                        resolution: r.resolution,
                        sample,
                    };
                    if prefetch.has(&key) {
                        continue;
                    }
                    let Ok(buffer) = self.pool.take() else { return };
                    if let Some(unused) = prefetch.request(key, buffer) {
                        self.pool.give(unused);
                    }
                }
            }
        }
    }

    /// The upload pass for what `prepare` read (None when all was resident).
    pub fn upload_pass(&self) -> GpuResult<Option<UploadPass<'_>>> {
        if self.pending.is_empty() {
            return Ok(None);
        }
        let mut uploads = Vec::new();
        for p in &self.pending {
            let class =
                self.sets.classes.get(p.class).ok_or_else(|| {
                    GpuError::Invalid(format!("internal: no map class {}", p.class))
                })?;
            let image = &class.arrays[p.layer];
            // Skip the dropped finest levels: they lead the staging layout.
            let layer = self.settings.layers()[p.layer];
            let offset = dropped_bytes(layer, class.resolution, self.settings.drop_levels)?;
            uploads.push(Upload {
                buffer: &p.buffer,
                offset,
                image,
                element: Some(p.element),
            });
        }
        Ok(Some(UploadPass {
            device: &self.device,
            uploads,
        }))
    }

    /// The passes that draw `blend`'s samples, before and after the room
    /// pass (`target` is the frame's, as the room pass leaves it).
    pub fn draw_passes<'a>(
        &'a self,
        gpu: &'a GpuScene,
        gbuffer: &'a GBuffer,
        blend: &SampleBlend,
        target: Target<'a>,
        view_proj: Mat4,
    ) -> GpuResult<AroundRoom<'a>> {
        let slots = self.slots_of(blend)?;
        if self.settings.deferred() {
            self.deferred_passes(gpu, gbuffer, blend, &slots, target, view_proj)
        } else {
            let passes = self.multipass(gpu, blend, &slots, target, view_proj)?;
            Ok(AroundRoom::after_room(passes))
        }
    }

    /// Each reflector's array element of every sample of `blend`.
    fn slots_of(&self, blend: &SampleBlend) -> GpuResult<Vec<Vec<u32>>> {
        self.reflectors
            .iter()
            .map(|r| {
                blend
                    .indices()
                    .map(|k| {
                        r.element(k).ok_or_else(|| {
                            GpuError::Invalid(format!(
                                "{}: sample {k} is not resident (prepare() first)",
                                r.name
                            ))
                        })
                    })
                    .collect()
            })
            .collect()
    }

    /// Waits for decoding ahead to finish (see `Prefetcher::wait_idle`).
    pub fn settle(&mut self) {
        if let Some(p) = self.prefetch.as_mut() {
            p.wait_idle();
        }
    }

    /// Staging buffers made so far.
    pub fn staging_buffers(&self) -> usize {
        self.pool.made()
    }
}

/// Groups the reflectors by EM resolution (in the order they first
/// appear): each reflector's class and its slots' first array element in
/// that class. Returns each class's resolution and member count.
fn assign_classes(reflectors: &mut [PemReflector]) -> Result<Vec<(u32, usize)>> {
    if reflectors.is_empty() {
        bail!("no reflector with [objects.em] settings to play");
    }
    let mut classes: Vec<(u32, usize)> = Vec::new();
    for r in reflectors.iter_mut() {
        let class = match classes.iter().position(|&(res, _)| res == r.resolution) {
            Some(c) => c,
            None => {
                classes.push((r.resolution, 0));
                classes.len() - 1
            }
        };
        r.class = class;
        r.base = (classes[class].1 * SLOTS) as u32;
        classes[class].1 += 1;
    }
    Ok(classes)
}

/// The array a `layer`'s maps play from: one element per slot of every
/// reflector, RGBA16F, full MIP chain from the level `drop` below the
/// finest of a reflector with `resolution`² EMs.
fn map_array(
    device: &Device,
    layer: MapLayer,
    (resolution, drop): (u32, u32),
    reflectors: usize,
) -> Result<Image> {
    let format = vk::Format::R16G16B16A16_SFLOAT;
    let count = (reflectors * SLOTS) as u32;
    let desc = match layer {
        MapLayer::Ptm => {
            let edge = ptm_edge(resolution) >> drop;
            ImageDesc::new_2d_array(format, edge, edge, count)
        }
        _ => ImageDesc::new_cube_array(format, resolution >> drop, count),
    }
    .all_mip_levels()
    .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
    Ok(Image::new(
        device,
        &format!("{} maps", layer.file_part()),
        desc,
    )?)
}

/// Bytes of the `drop` finest levels in the staging layout.
fn dropped_bytes(layer: MapLayer, resolution: u32, drop: u32) -> GpuResult<u64> {
    if drop == 0 {
        return Ok(0);
    }
    let desc = match layer {
        MapLayer::Ptm => {
            let edge = ptm_edge(resolution);
            ImageDesc::new_2d(vk::Format::R16G16B16A16_SFLOAT, edge, edge)
        }
        _ => ImageDesc::new_cube(vk::Format::R16G16B16A16_SFLOAT, resolution),
    }
    .all_mip_levels();
    let (regions, _) = level_regions(&desc)?;
    Ok(regions.get(drop as usize).map_or(0, |r| r.buffer_offset))
}
