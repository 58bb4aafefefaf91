//! PEM playback: per frame, texgen for every reflector, the samples the
//! eye needs made resident (decoded ahead on the worker, or now), and the
//! passes that draw them — deferred (G-buffer, then one compositing pass
//! shading each covered pixel once) or the papers' multipass — only what
//! the scene and the eye need: no local layer on convex-hull triangles, one
//! sample exactly on a grid line.

use super::ahead::{TexgenFrame, TexgenInputs, TexgenRequest};
use super::filling::{MakeHostReadable, Pending, map_arrays};
use super::frame_sets::FrameSets;
use super::prefetch::Prefetcher;
use super::reflector::PemReflector;
use super::residency::SLOTS;
use super::samples::{SampleBlend, ViewGrid};
pub use super::settings::{Compositing, PemKind, PemSettings};
use super::source::{MapLayer, MapSource};
use super::staging::StagingPool;
use crate::backend::{Device, GpuError, GpuResult};
use crate::gpu_scene::GpuScene;
use crate::graph::Executor;
use crate::passes::pem_deferred::GBuffer;
use crate::passes::target::{AroundRoom, Target};
use anyhow::{Result, bail};
use ash::vk;
use glam::{Mat4, Vec3};
use inference::scene::{Material, Orbit, Scene};
use std::time::Instant;

/// CPU costs of preparing one PEM frame, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct PemCpu {
    pub texgen_ms: f64,
    /// Decoding on the frame (maps not decoded ahead).
    pub decode_ms: f64,
    pub decoded_maps: u32,
    /// Maps the worker had decoded ahead, straight into their slots or
    /// into staging.
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
    pub(super) pool: StagingPool,
    pub(super) pending: Vec<Pending>,
    pub(super) source: MapSource,
    pub(super) prefetch: Option<Prefetcher>,
    pub(super) grid: ViewGrid,
    pub(super) orbit: Orbit,
    pub(super) last_angles: Option<(f32, f32)>,
    pub(super) frame: u64,
    /// Maps are decoded straight into host-written slot arrays (the device
    /// samples linear images: lavapipe), not uploaded from staging.
    pub(super) host_slots: bool,
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
        let (classes, host_slots) = map_arrays(device, &settings, &resolutions)?;
        let sets = FrameSets::new(device, executor, &settings, classes, gbuffer, formats)?;
        if host_slots {
            // Before any host write (the worker starts with the first frame).
            executor.run(&[&MakeHostReadable(sets.arrays().collect())])?;
        }
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
            host_slots,
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
    /// `blend`'s samples that are not resident into their slots (or
    /// staging). The previous frame has run (its fence was waited on), so
    /// its staging buffers go back to the pool first. `next_eye`, when the
    /// caller knows it, is where the next frame looks from: its samples are
    /// decoded ahead (without it, those of the next cell along the eye's
    /// last move).
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
            self.settle_ahead(ri, &needed, &mut cpu);
            let mut fills = self.reflectors[ri].table.assign(&needed, self.frame);
            if fills.is_none() {
                // Slots filled ahead for other samples hold the room this
                // frame needs: let them finish, then they may go.
                let filling: Vec<u32> = (self.reflectors[ri].table.filling_slots())
                    .into_iter()
                    .map(|(_, k)| k)
                    .collect();
                self.settle_ahead(ri, &filling, &mut cpu);
                fills = self.reflectors[ri].table.assign(&needed, self.frame);
            }
            let Some(fills) = fills else {
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
        // The announced view is exact; only without one is the next cell
        // guessed from the last move (a wrong guess decodes maps no frame
        // reads: 56 of 322 on the main job's path).
        if let Some(next) = next_eye {
            self.prefetch_blend(&self.blend(next), &needed);
        }
        self.prefetch_next(eye, &needed, next_eye.is_none());
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

    /// Each map the worker decoded since the last call: its wall time,
    /// while the device rendered on the same cores.
    pub fn drain_ahead_decode_ms(&mut self) -> Vec<f64> {
        self.prefetch
            .as_mut()
            .map_or_else(Vec::new, |p| p.drain_decode_ms())
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
