//! PEM playback: per frame, texgen for every reflector, the samples the
//! eye needs made resident (decoded ahead on the worker, or now), and the
//! passes that draw them — only those the scene and the eye need: no
//! local layer on convex-hull triangles, no blend pass exactly on a sample.

use super::prefetch::{MapKey, Prefetcher, decode_into};
use super::reflector::{PemReflector, SlotBindings, map_desc};
use super::samples::SampleBlend;
pub use super::settings::{PemKind, PemSettings};
use super::source::{MapLayer, MapSource};
use super::staging::StagingPool;
use crate::backend::upload::level_regions;
use crate::backend::{Buffer, Device, GpuError, GpuResult, Image, Sampler};
use crate::gpu_scene::GpuScene;
use crate::graph::Executor;
use crate::passes::mirror::fresnel_lut_image;
use crate::passes::pem::{PemDraw, PemPass, PemPipelines, Shading};
use crate::passes::target::{Target, area_of};
use crate::passes::upload::{Upload, UploadPass};
use anyhow::{Result, bail};
use ash::vk;
use glam::{Mat4, Vec3};
use inference::scene::{Material, Scene};
use inference::texgen::TexgenVertex;
use std::time::Instant;

/// A map read into staging this frame, waiting for its upload pass.
struct Pending {
    reflector: usize,
    slot: usize,
    layer: usize,
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
}

pub struct PemPlayer {
    device: Device,
    pub settings: PemSettings,
    pipelines: PemPipelines,
    lut: Image,
    /// (cube, 2D): alive as long as the slots' descriptor sets.
    _samplers: (Sampler, Sampler),
    reflectors: Vec<PemReflector>,
    pool: StagingPool,
    pending: Vec<Pending>,
    source: MapSource,
    prefetch: Option<Prefetcher>,
    samples: u32,
    last_position: Option<f32>,
    frame: u64,
    scratch: Vec<TexgenVertex>,
}

impl PemPlayer {
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        scene: &Scene,
        settings: PemSettings,
        source: MapSource,
        formats: (vk::Format, vk::Format),
    ) -> Result<Self> {
        let pipelines = PemPipelines::new(device, formats.0, formats.1)?;
        let lut = fresnel_lut_image(device, executor)?;
        let cube = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            settings.filtering,
        )?;
        let flat = Sampler::new(device, vk::SamplerAddressMode::REPEAT, settings.filtering)?;
        let bindings = SlotBindings {
            pipelines: &pipelines,
            lut: &lut,
            cube: &cube,
            flat: &flat,
        };
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
            reflectors.push(PemReflector::new(
                device,
                scene,
                (index, o),
                f0,
                &settings,
                &bindings,
            )?);
        }
        let leaf_bytes = reflectors
            .iter()
            .flat_map(|r| layers.iter().map(|l| l.layout(r.resolution).len() * 8))
            .max()
            .unwrap_or(0);
        Ok(Self {
            device: device.clone(),
            settings,
            pipelines,
            lut,
            _samplers: (cube, flat),
            reflectors,
            pool: StagingPool::new(device, leaf_bytes as u64),
            pending: Vec::new(),
            // Without a second handle playback still works, decoding in line.
            prefetch: source.reopen().ok().map(Prefetcher::new),
            source,
            samples: scene.orbit.samples,
            last_position: None,
            frame: 0,
            scratch: Vec::new(),
        })
    }

    /// Forgets every image's tracked state before they are destroyed.
    pub fn release(&self, executor: &mut Executor) {
        executor.states.forget(&self.lut);
        for r in &self.reflectors {
            for i in r.slots.iter().flat_map(|s| &s.images) {
                executor.states.forget(i);
            }
        }
    }

    /// CPU work before recording a frame: texgen for `eye`, and the maps of
    /// `blend`'s samples that are not resident into staging. The previous
    /// frame's uploads have run (its fence was waited on), so their
    /// staging buffers go back to the pool first.
    pub fn prepare(&mut self, eye: Vec3, blend: &SampleBlend) -> Result<PemCpu> {
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
        let needed: Vec<u32> = blend.samples().collect();
        for ri in 0..self.reflectors.len() {
            let start = Instant::now();
            self.reflectors[ri].texgen(eye, &self.settings, &mut self.scratch)?;
            cpu.texgen_ms += start.elapsed().as_secs_f64() * 1e3;
            let Some(fills) = self.reflectors[ri].table.assign(&needed, self.frame) else {
                bail!("internal: {} samples do not fit the slots", needed.len());
            };
            for (sample, slot) in fills {
                self.fill_slot(ri, slot, sample, &mut cpu)?;
            }
        }
        self.prefetch_next(blend);
        Ok(cpu)
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
            let buffer = match self.prefetch.as_mut().and_then(|p| p.take(&key)) {
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
                reflector: ri,
                slot,
                layer: layer_index,
                buffer,
            });
        }
        Ok(())
    }

    /// Asks the worker for the sample beyond `blend` in the direction the
    /// eye moves, for every reflector that does not hold it yet.
    fn prefetch_next(&mut self, blend: &SampleBlend) {
        let position = match blend.second {
            Some((s, w)) => blend.first as f32 * (1.0 - w) + s as f32 * w,
            None => blend.first as f32,
        };
        let last = self.last_position.replace(position);
        let (Some(last), Some(prefetch)) = (last, self.prefetch.as_mut()) else {
            return;
        };
        let step = self.settings.spacing.max(1) as i64;
        let ahead = match position.partial_cmp(&last) {
            Some(std::cmp::Ordering::Greater) => blend.samples().max().map(|s| s as i64 + step),
            Some(std::cmp::Ordering::Less) => blend.samples().min().map(|s| s as i64 - step),
            _ => None,
        };
        let Some(next) = ahead.filter(|&s| s >= 0 && s < i64::from(self.samples)) else {
            return;
        };
        for r in self
            .reflectors
            .iter()
            .filter(|r| !r.table.holds(next as u32))
        {
            for layer in self.settings.layers() {
                let key = MapKey {
                    object: r.name.clone(),
                    layer,
                    resolution: r.resolution,
                    sample: next as u32,
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

    /// The upload pass for what `prepare` read (None when all was resident).
    pub fn upload_pass(&self) -> GpuResult<Option<UploadPass<'_>>> {
        if self.pending.is_empty() {
            return Ok(None);
        }
        let mut uploads = Vec::new();
        for p in &self.pending {
            let r = &self.reflectors[p.reflector];
            let image = &r.slots[p.slot].images[p.layer];
            // Skip the dropped finest levels: they lead the staging layout.
            let layer = self.settings.layers()[p.layer];
            let offset = dropped_bytes(layer, r.resolution, self.settings.drop_levels)?;
            uploads.push(Upload {
                buffer: &p.buffer,
                offset,
                image,
            });
        }
        Ok(Some(UploadPass {
            device: &self.device,
            uploads,
        }))
    }

    /// The draw passes for `blend`: the first sample replacing what the
    /// room pass drew, the second (if any) blended over it by its weight.
    pub fn draw_passes<'a>(
        &'a self,
        gpu: &'a GpuScene,
        blend: &SampleBlend,
        target: Target<'a>,
        view_proj: Mat4,
    ) -> GpuResult<Vec<PemPass<'a>>> {
        let extent = target.extent();
        let area = area_of(
            view_proj,
            self.reflectors.iter().map(|r| r.bounds),
            extent.width,
            extent.height,
        );
        let mut samples = vec![(blend.first, 1.0, false, "pem")];
        if let Some((s, w)) = blend.second {
            samples.push((s, w, true, "pem_blend"));
        }
        let mut passes = Vec::new();
        for (sample, weight, is_blend, name) in samples {
            let mut draws = Vec::new();
            let mut sampled = vec![&self.lut];
            for r in &self.reflectors {
                let slot = r
                    .table
                    .find(sample)
                    .and_then(|i| r.slots.get(i))
                    .ok_or_else(|| {
                        GpuError::Invalid(format!(
                            "{}: sample {sample} is not resident (prepare() first)",
                            r.name
                        ))
                    })?;
                sampled.extend(slot.images.iter());
                draws.extend(self.draws_of(gpu, r, slot)?);
            }
            passes.push(PemPass {
                name,
                device: &self.device,
                pipelines: &self.pipelines,
                blend: is_blend,
                weight,
                draws,
                sampled,
                target: Target {
                    clear: false,
                    area,
                    ..target
                },
                view_proj,
            });
        }
        Ok(passes)
    }

    /// A reflector's draws of one sample: hull triangles with the distant
    /// layer alone and the rest with both (layered), or one draw.
    fn draws_of<'a>(
        &self,
        gpu: &'a GpuScene,
        r: &'a PemReflector,
        slot: &super::reflector::Slot,
    ) -> GpuResult<Vec<PemDraw<'a>>> {
        let Some(mesh) = gpu.meshes.get(r.object) else {
            return Err(GpuError::Invalid(format!("{}: no GPU mesh", r.name)));
        };
        let texgen =
            (self.settings.kind != PemKind::Ptm).then_some((&r.texgen_distant, &r.texgen_local));
        let draw = |shading, set, first_index, index_count| PemDraw {
            shading,
            set,
            mesh,
            indices: &r.indices,
            first_index,
            index_count,
            texgen,
            f0: r.f0,
        };
        Ok(match (self.settings.kind, slot.hull_set) {
            (PemKind::Layered, Some(hull_set)) => vec![
                draw(Shading::SingleEm, hull_set, 0, r.hull_index_count),
                draw(
                    Shading::Layered,
                    slot.set,
                    r.hull_index_count,
                    r.index_count - r.hull_index_count,
                ),
            ],
            (PemKind::Ptm, _) => vec![draw(Shading::Ptm, slot.set, 0, r.index_count)],
            _ => vec![draw(Shading::SingleEm, slot.set, 0, r.index_count)],
        })
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

/// Bytes of the `drop` finest levels in the staging layout.
fn dropped_bytes(layer: MapLayer, resolution: u32, drop: u32) -> GpuResult<u64> {
    if drop == 0 {
        return Ok(0);
    }
    let (regions, _) = level_regions(&map_desc(layer, resolution))?;
    Ok(regions.get(drop as usize).map_or(0, |r| r.buffer_offset))
}
