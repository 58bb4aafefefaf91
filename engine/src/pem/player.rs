//! PEM playback state: per reflector its hull-sorted indices, texgen
//! streams and a few resident sample slots (GPU images filled from a
//! staging ring), and per frame the passes that draw it — only those the
//! scene and the eye need: no local layer on convex-hull triangles, no
//! blend pass exactly on a sample.

use super::prefetch::{MapKey, Prefetcher};
use super::samples::SampleBlend;
use super::source::{MapLayer, MapSource};
use crate::backend::upload::level_regions;
use crate::backend::{
    Binding, Buffer, Device, Filtering, GpuError, GpuResult, Image, ImageDesc, Sampler,
};
use crate::gpu_scene::GpuScene;
use crate::graph::Executor;
use crate::passes::mirror::fresnel_lut_image;
use crate::passes::pem::{PemDraw, PemPass, PemPipelines, Shading};
use crate::passes::target::{Target, area_of};
use crate::passes::upload::{Upload, UploadPass};
use ash::vk;
use glam::{Mat4, Vec3};
use gpu_allocator::MemoryLocation;
use half::f16;
use inference::em_geometry::{EmGeometry, bounding_ellipsoid, texgen};
use inference::scene::{Material, Scene};
use inference::texgen::TexgenVertex;
use std::time::Instant;

/// What PEM playback draws: the knobs that trade speed for accuracy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PemSettings {
    pub kind: PemKind,
    /// Layered PEMs: draw the local layer (false = distant layer only).
    pub local_layer: bool,
    /// Blend the two nearest samples (false = nearest only).
    pub blend: bool,
    /// Use every `spacing`-th sample only (1 = all).
    pub spacing: u32,
    /// Finest MIP levels dropped: the EM resolution is `res >> drop_levels`.
    pub drop_levels: u32,
    pub filtering: Filtering,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PemKind {
    /// Distant box + local ellipsoid layers (the PEM paper's method).
    Layered,
    /// One sphere-at-infinity EM per sample.
    Sphere,
    /// Parameterized texture maps on the surface.
    Ptm,
}

impl PemSettings {
    pub fn new(kind: PemKind) -> Self {
        Self {
            kind,
            local_layer: true,
            blend: true,
            spacing: 1,
            drop_levels: 0,
            filtering: Filtering::Trilinear,
        }
    }

    /// The maps one sample needs, in slot order.
    pub fn layers(&self) -> Vec<MapLayer> {
        match self.kind {
            PemKind::Layered if self.local_layer => vec![MapLayer::Distant, MapLayer::Local],
            PemKind::Layered => vec![MapLayer::Distant],
            PemKind::Sphere => vec![MapLayer::Sphere],
            PemKind::Ptm => vec![MapLayer::Ptm],
        }
    }
}

/// Samples kept resident per reflector: the two a blend needs plus one,
/// so moving back and forth across a sample does not re-decode.
const SLOTS: usize = 3;

/// One resident sample's maps and the descriptor sets that sample them.
struct Slot {
    sample: Option<u32>,
    last_used: u64,
    images: Vec<Image>,
    /// Binds every layer (+ the LUT for EMs).
    set: vk::DescriptorSet,
    /// Layered PEMs: the distant layer alone, for hull triangles.
    hull_set: Option<vk::DescriptorSet>,
}

struct Reflector {
    object: usize,
    name: String,
    f0: Vec3,
    resolution: u32,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    origin: Vec3,
    /// World-space bounds: what the draw passes' render area must cover.
    bounds: (Vec3, Vec3),
    distant: EmGeometry,
    local: EmGeometry,
    /// Triangles on the convex hull first, then the rest.
    indices: Buffer,
    hull_index_count: u32,
    index_count: u32,
    texgen_distant: Buffer,
    texgen_local: Buffer,
    slots: Vec<Slot>,
}

/// A map read into staging this frame, waiting for its upload pass.
struct Pending {
    reflector: usize,
    slot: usize,
    layer: usize,
    staging: usize,
}

/// CPU costs of preparing one PEM frame, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct PemCpu {
    pub texgen_ms: f64,
    pub decode_ms: f64,
    pub decoded_maps: u32,
    /// Maps the worker had decoded ahead (their copy is in `decode_ms`).
    pub prefetched_maps: u32,
}

pub struct PemPlayer {
    device: Device,
    pub settings: PemSettings,
    pipelines: PemPipelines,
    lut: Image,
    /// (cube, 2D): alive as long as the slots' descriptor sets.
    _samplers: (Sampler, Sampler),
    reflectors: Vec<Reflector>,
    staging: Vec<Buffer>,
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
        color: vk::Format,
        depth: vk::Format,
    ) -> anyhow::Result<Self> {
        let pipelines = PemPipelines::new(device, color, depth)?;
        let lut = fresnel_lut_image(device, executor)?;
        let cube_sampler = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            settings.filtering,
        )?;
        let flat_sampler =
            Sampler::new(device, vk::SamplerAddressMode::REPEAT, settings.filtering)?;
        let (room_min, room_max) = scene.bounds();
        let layers = settings.layers();
        let mut reflectors = Vec::new();
        for (object, o) in scene.objects.iter().enumerate() {
            let f0 = match scene.materials.get(o.material) {
                Some(Material::Mirror { f0 }) | Some(Material::Glossy { f0, .. }) => *f0,
                _ => continue,
            };
            let Some(em) = o.em.as_ref() else { continue };
            let resolution = em.resolution.max(1);
            if settings.drop_levels >= 32 - resolution.leading_zeros() {
                anyhow::bail!(
                    "{}: dropping {} MIP levels of a {resolution}² map leaves none",
                    o.name,
                    settings.drop_levels
                );
            }
            for &layer in &layers {
                if !source.has(&o.name, layer) {
                    anyhow::bail!(
                        "no {}.{} maps to play (run `engine infer --scene {}{}`)",
                        o.name,
                        layer.file_part(),
                        scene.arg(),
                        if layer == MapLayer::Sphere {
                            " --all --sphere"
                        } else {
                            " --all"
                        }
                    );
                }
            }
            let origin = o.mesh.area_weighted_centroid();
            // Convex-hull triangles cannot see the reflector: distant EM only.
            let hull = inference::hull::hull_triangles(&o.mesh);
            let (indices, hull_index_count) = hull_sorted_indices(&o.mesh.indices, &hull);
            let n = o.mesh.positions.len();
            let stream = |name: &str| {
                Buffer::new(
                    device,
                    name,
                    (n * size_of::<TexgenVertex>()) as u64,
                    vk::BufferUsageFlags::VERTEX_BUFFER,
                    MemoryLocation::CpuToGpu,
                )
            };
            let mut r = Reflector {
                object,
                name: o.name.clone(),
                f0,
                resolution,
                positions: o.mesh.positions.clone(),
                normals: o.mesh.normals.clone(),
                origin,
                bounds: o.mesh.bounds(),
                distant: EmGeometry::Box {
                    min: room_min,
                    max: room_max,
                },
                local: EmGeometry::Ellipsoid {
                    center: origin,
                    radii: bounding_ellipsoid(origin, &o.mesh.positions),
                },
                indices: Buffer::with_data(
                    device,
                    &format!("{} hull-sorted indices", o.name),
                    vk::BufferUsageFlags::INDEX_BUFFER,
                    &indices,
                )?,
                hull_index_count,
                index_count: indices.len() as u32,
                texgen_distant: stream("texgen distant")?,
                texgen_local: stream("texgen local")?,
                slots: Vec::new(),
            };
            for _ in 0..SLOTS {
                let slot = make_slot(
                    device,
                    &pipelines,
                    &settings,
                    &layers,
                    &r,
                    &lut,
                    &cube_sampler,
                    &flat_sampler,
                )?;
                r.slots.push(slot);
            }
            reflectors.push(r);
        }
        // Enough staging for every map of two samples of every reflector.
        let leaf_bytes = reflectors
            .iter()
            .flat_map(|r| layers.iter().map(|l| leaf_halves(*l, r.resolution) * 2))
            .max()
            .unwrap_or(0);
        let staging = (0..2 * layers.len() * reflectors.len())
            .map(|i| {
                Buffer::new(
                    device,
                    &format!("map staging {i}"),
                    leaf_bytes as u64,
                    vk::BufferUsageFlags::TRANSFER_SRC,
                    MemoryLocation::CpuToGpu,
                )
            })
            .collect::<GpuResult<Vec<_>>>()?;
        Ok(Self {
            device: device.clone(),
            settings,
            pipelines,
            lut,
            _samplers: (cube_sampler, flat_sampler),
            reflectors,
            staging,
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
            for s in &r.slots {
                for i in &s.images {
                    executor.states.forget(i);
                }
            }
        }
    }

    /// CPU work before recording a frame: texgen for `eye`, and the maps of
    /// `blend`'s samples that are not resident read into staging.
    pub fn prepare(&mut self, eye: Vec3, blend: &SampleBlend) -> anyhow::Result<PemCpu> {
        self.frame += 1;
        let mut cpu = PemCpu::default();
        self.pending.clear();
        let layers = self.settings.layers();
        let mut next_staging = 0;
        for (ri, r) in self.reflectors.iter_mut().enumerate() {
            let start = Instant::now();
            if self.settings.kind != PemKind::Ptm {
                let n = r.positions.len();
                self.scratch.resize(n, [0.0; 4]);
                let first = match self.settings.kind {
                    PemKind::Sphere => EmGeometry::SphereAtInfinity,
                    _ => r.distant,
                };
                let mut streams = vec![(first, &mut r.texgen_distant)];
                if self.settings.kind == PemKind::Layered && self.settings.local_layer {
                    streams.push((r.local, &mut r.texgen_local));
                }
                for (geometry, buffer) in streams {
                    texgen(
                        &geometry,
                        r.origin,
                        eye,
                        &r.positions,
                        &r.normals,
                        &mut self.scratch,
                    );
                    let bytes: &[u8] = bytemuck::cast_slice(&self.scratch);
                    buffer.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
                }
            }
            cpu.texgen_ms += start.elapsed().as_secs_f64() * 1e3;
            let needed: Vec<u32> = blend.samples().collect();
            for &sample in &needed {
                if let Some(slot) = r.slots.iter_mut().find(|s| s.sample == Some(sample)) {
                    slot.last_used = self.frame;
                    continue;
                }
                // Replace the least recently used slot this frame does not need.
                let Some(slot_index) = (0..r.slots.len())
                    .filter(|&i| r.slots[i].sample.is_none_or(|s| !needed.contains(&s)))
                    .min_by_key(|&i| r.slots[i].last_used)
                else {
                    anyhow::bail!("no free map slot (internal: {SLOTS} slots, 2 samples)");
                };
                for (li, &layer) in layers.iter().enumerate() {
                    let Some(staging) = self.staging.get_mut(next_staging) else {
                        anyhow::bail!("staging ring exhausted (internal)");
                    };
                    let halves = leaf_halves(layer, r.resolution);
                    let bytes = &mut staging.mapped_mut()?[..halves * 2];
                    let out: &mut [f16] = bytemuck::try_cast_slice_mut(bytes)
                        .map_err(|e| anyhow::anyhow!("staging buffer not f16-aligned: {e}"))?;
                    let key = MapKey {
                        object: r.name.clone(),
                        layer,
                        resolution: r.resolution,
                        sample,
                    };
                    let read_start = Instant::now();
                    match self.prefetch.as_mut().and_then(|p| p.take(&key)) {
                        Some((texels, _)) if texels.len() == out.len() => {
                            out.copy_from_slice(&texels);
                            cpu.prefetched_maps += 1;
                        }
                        _ => self
                            .source
                            .read(&r.name, layer, r.resolution, sample, out)?,
                    }
                    cpu.decode_ms += read_start.elapsed().as_secs_f64() * 1e3;
                    cpu.decoded_maps += 1;
                    self.pending.push(Pending {
                        reflector: ri,
                        slot: slot_index,
                        layer: li,
                        staging: next_staging,
                    });
                    next_staging += 1;
                }
                let slot = &mut r.slots[slot_index];
                slot.sample = Some(sample);
                slot.last_used = self.frame;
            }
        }
        self.prefetch_next(blend, &layers);
        Ok(cpu)
    }

    /// Asks the worker for the sample beyond `blend` in the direction the
    /// eye moves, for every reflector that does not hold it yet.
    fn prefetch_next(&mut self, blend: &SampleBlend, layers: &[MapLayer]) {
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
        let next = next as u32;
        for r in &self.reflectors {
            if r.slots.iter().any(|s| s.sample == Some(next)) {
                continue;
            }
            for &layer in layers {
                prefetch.request(MapKey {
                    object: r.name.clone(),
                    layer,
                    resolution: r.resolution,
                    sample: next,
                });
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
                buffer: &self.staging[p.staging],
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
        let mut passes = Vec::new();
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
        for (sample, weight, is_blend, name) in samples {
            let mut draws = Vec::new();
            let mut sampled = vec![&self.lut];
            for r in &self.reflectors {
                let Some(slot) = r.slots.iter().find(|s| s.sample == Some(sample)) else {
                    return Err(GpuError::Invalid(format!(
                        "{}: sample {sample} is not resident (prepare() first)",
                        r.name
                    )));
                };
                let Some(mesh) = gpu.meshes.get(r.object) else {
                    return Err(GpuError::Invalid(format!("{}: no GPU mesh", r.name)));
                };
                sampled.extend(slot.images.iter());
                let texgen = (self.settings.kind != PemKind::Ptm)
                    .then_some((&r.texgen_distant, &r.texgen_local));
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
                match (self.settings.kind, slot.hull_set) {
                    (PemKind::Layered, Some(hull_set)) => {
                        draws.push(draw(Shading::SingleEm, hull_set, 0, r.hull_index_count));
                        draws.push(draw(
                            Shading::Layered,
                            slot.set,
                            r.hull_index_count,
                            r.index_count - r.hull_index_count,
                        ));
                    }
                    (PemKind::Ptm, _) => draws.push(draw(Shading::Ptm, slot.set, 0, r.index_count)),
                    _ => draws.push(draw(Shading::SingleEm, slot.set, 0, r.index_count)),
                }
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

    /// Waits for decoding ahead to finish (see `Prefetcher::wait_idle`).
    pub fn settle(&mut self) {
        if let Some(p) = self.prefetch.as_mut() {
            p.wait_idle();
        }
    }
}

/// The images of one sample slot and its descriptor sets.
#[allow(clippy::too_many_arguments)]
fn make_slot(
    device: &Device,
    pipelines: &PemPipelines,
    settings: &PemSettings,
    layers: &[MapLayer],
    r: &Reflector,
    lut: &Image,
    cube_sampler: &Sampler,
    flat_sampler: &Sampler,
) -> anyhow::Result<Slot> {
    let size = r.resolution >> settings.drop_levels;
    let mut images = Vec::new();
    for layer in layers {
        let desc = map_desc(*layer, size)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
        images.push(Image::new(
            device,
            &format!("{} {} slot", r.name, layer.file_part()),
            desc,
        )?);
    }
    let lut_binding = Binding::Image(lut.view, cube_sampler.raw);
    let cube = |i: usize| Binding::Image(images[i].view, cube_sampler.raw);
    let (set, hull_set) = match settings.kind {
        PemKind::Layered if layers.len() == 2 => (
            pipelines.get(Shading::Layered, false).descriptor_set(&[
                cube(0),
                cube(1),
                lut_binding,
            ])?,
            Some(
                pipelines
                    .get(Shading::SingleEm, false)
                    .descriptor_set(&[cube(0), lut_binding])?,
            ),
        ),
        PemKind::Ptm => (
            pipelines
                .get(Shading::Ptm, false)
                .descriptor_set(&[Binding::Image(images[0].view, flat_sampler.raw)])?,
            None,
        ),
        _ => (
            pipelines
                .get(Shading::SingleEm, false)
                .descriptor_set(&[cube(0), lut_binding])?,
            None,
        ),
    };
    Ok(Slot {
        sample: None,
        last_used: 0,
        images,
        set,
        hull_set,
    })
}

/// The image a `size` map of `layer` plays from: RGBA16F, full MIP chain.
fn map_desc(layer: MapLayer, size: u32) -> ImageDesc {
    let format = vk::Format::R16G16B16A16_SFLOAT;
    match layer {
        MapLayer::Ptm => ImageDesc::new_2d(format, size, size),
        _ => ImageDesc::new_cube(format, size),
    }
    .all_mip_levels()
}

/// f16 components of a whole leaf map (RGBA, full MIP chain).
fn leaf_halves(layer: MapLayer, resolution: u32) -> usize {
    inference::solve::layout::TextureLayout::full_chain(layer.shape(resolution)).len() * 4
}

/// Bytes of the `drop` finest levels in the staging layout.
fn dropped_bytes(layer: MapLayer, resolution: u32, drop: u32) -> GpuResult<u64> {
    if drop == 0 {
        return Ok(0);
    }
    let (regions, _) = level_regions(&map_desc(layer, resolution))?;
    Ok(regions.get(drop as usize).map_or(0, |r| r.buffer_offset))
}

/// The mesh's indices with hull triangles first, and how many indices
/// those are.
pub fn hull_sorted_indices(indices: &[u32], hull: &[bool]) -> (Vec<u32>, u32) {
    let triangles = indices
        .chunks_exact(3)
        .zip(hull.iter().chain(std::iter::repeat(&false)));
    let mut sorted: Vec<u32> = triangles
        .clone()
        .filter(|(_, on)| **on)
        .flat_map(|(t, _)| t.iter().copied())
        .collect();
    let hull_count = sorted.len() as u32;
    sorted.extend(
        triangles
            .filter(|(_, on)| !**on)
            .flat_map(|(t, _)| t.iter().copied()),
    );
    (sorted, hull_count)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_sorting_keeps_every_triangle_once() {
        let indices = [0, 1, 2, 3, 4, 5, 6, 7, 8];
        let (sorted, hull) = hull_sorted_indices(&indices, &[false, true, false]);
        assert_eq!(hull, 3);
        assert_eq!(sorted, [3, 4, 5, 0, 1, 2, 6, 7, 8]);
        // Missing flags count as "not on the hull".
        let (sorted, hull) = hull_sorted_indices(&indices, &[true]);
        assert_eq!((sorted.len(), hull), (9, 3));
    }
}
