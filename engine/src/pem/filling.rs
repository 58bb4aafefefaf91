//! Filling the reflectors' slots with the samples a frame needs, and ahead
//! of need. Where the device can sample host-written arrays (lavapipe), a
//! sample's maps are decoded straight into its slot — by the worker while
//! the device draws other slots, or on the frame — with no staging copy
//! and no upload pass; elsewhere they go through staging buffers and the
//! `upload` pass.

use super::player::{PemCpu, PemPlayer, PemSettings};
use super::prefetch::{Job, MapKey, decode_into};
use super::residency::SLOTS;
use super::samples::SampleBlend;
use super::source::MapLayer;
use crate::backend::host_image::HostElement;
use crate::backend::upload::level_regions;
use crate::backend::{Buffer, Device, GpuError, GpuResult, Image, ImageDesc};
use crate::graph::{Access, Pass, Usage};
use crate::maps::ptm_edge;
use crate::passes::upload::{Upload, UploadPass};
use anyhow::Result;
use ash::vk;
use std::sync::Arc;
use std::time::Instant;

/// A map read into staging this frame, waiting for its upload pass.
pub(super) struct Pending {
    pub class: usize,
    pub layer: usize,
    pub element: u32,
    pub buffer: Buffer,
}

impl PemPlayer {
    fn key(&self, ri: usize, layer: MapLayer, sample: u32) -> MapKey {
        let r = &self.reflectors[ri];
        MapKey {
            object: r.name.clone(),
            layer,
            resolution: r.resolution,
            sample,
        }
    }

    /// The slots of reflector `ri` the worker has been filling: those it
    /// finished become readable (a failed one empty, to be filled on the
    /// frame if needed), and those `needed` reads are waited for.
    pub(super) fn settle_ahead(&mut self, ri: usize, needed: &[u32], cpu: &mut PemCpu) {
        let layers = self.settings.layers();
        let Some(first) = layers.first().copied() else {
            return;
        };
        for (slot, sample) in self.reflectors[ri].table.filling_slots() {
            let key = self.key(ri, first, sample);
            let wait = needed.contains(&sample);
            let start = Instant::now();
            let done = match self.prefetch.as_mut() {
                Some(p) => p.take_slot(&key, wait),
                None => Some(Err(())),
            };
            if wait {
                cpu.prefetch_wait_ms += start.elapsed().as_secs_f64() * 1e3;
            }
            let table = &mut self.reflectors[ri].table;
            match done {
                Some(Ok(_)) => {
                    table.filled(slot);
                    cpu.prefetched_maps += layers.len() as u32;
                    cpu.decoded_maps += layers.len() as u32;
                }
                Some(Err(())) => table.abandon(slot),
                // Still running, or (waited for) the worker is gone.
                None if wait => table.abandon(slot),
                None => {}
            }
        }
    }

    /// Every layer of `sample` into slot `slot` of reflector `ri`, on the
    /// frame (the device is idle: the last frame's fence was waited on).
    pub(super) fn fill_slot(
        &mut self,
        ri: usize,
        slot: usize,
        sample: u32,
        cpu: &mut PemCpu,
    ) -> Result<()> {
        let (class, element) = {
            let r = &self.reflectors[ri];
            (r.class, r.base + slot as u32)
        };
        for (layer_index, &layer) in self.settings.layers().iter().enumerate() {
            let key = self.key(ri, layer, sample);
            if self.host_slots {
                let start = Instant::now();
                let mut target = self.lend(class, layer_index, element)?;
                let k = (key.object.as_str(), layer, key.resolution, sample);
                self.source
                    .read_into_slot(k, &mut target, self.settings.drop_levels)?;
                cpu.decode_ms += start.elapsed().as_secs_f64() * 1e3;
                cpu.decoded_maps += 1;
                continue;
            }
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
                class,
                layer: layer_index,
                element,
                buffer,
            });
        }
        Ok(())
    }

    /// Array element `element` of class `class`'s `layer_index`th array,
    /// lent for the host to write.
    fn lend(&self, class: usize, layer_index: usize, element: u32) -> Result<HostElement> {
        let array = self
            .sets
            .classes
            .get(class)
            .and_then(|c| c.arrays.get(layer_index))
            .ok_or_else(|| anyhow::anyhow!("internal: no array {layer_index} in class {class}"))?;
        Ok(HostElement::lend(array, element)?)
    }

    /// Notes where the eye moved and, with `guess`, asks the worker for
    /// the samples of the next cell in that direction, for every reflector
    /// that does not hold them yet. `keep`: what the frame being prepared
    /// reads.
    pub(super) fn prefetch_next(&mut self, eye: glam::Vec3, keep: &[u32], guess: bool) {
        let (az, el) = self.orbit.angles(eye);
        let last = self.last_angles.replace((az, el));
        let Some((last_az, last_el)) = last.filter(|_| guess) else {
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
        self.prefetch_blend(&ahead, keep);
    }

    /// Asks the worker for `blend`'s samples, every layer, for every
    /// reflector that does not hold them and has not asked yet; `keep`
    /// (what the frame being prepared reads) keeps its slots.
    pub(super) fn prefetch_blend(&mut self, blend: &SampleBlend, keep: &[u32]) {
        if self.prefetch.is_none() {
            return;
        }
        // Neither what this frame reads nor what `blend` finds resident
        // may make room for the rest of `blend`.
        let keep: Vec<u32> = keep.iter().copied().chain(blend.indices()).collect();
        for ri in 0..self.reflectors.len() {
            for sample in blend.indices() {
                if self.reflectors[ri].table.holds(sample) {
                    continue;
                }
                let asked = match self.host_slots {
                    true => self.prefetch_into_slot(ri, sample, &keep),
                    false => self.prefetch_staging(ri, sample),
                };
                if !asked {
                    break; // no room left in this reflector's slots
                }
            }
        }
    }

    /// Reserves a slot for `sample` of reflector `ri` and has the worker
    /// decode every layer into it; false when no slot or worker is left.
    fn prefetch_into_slot(&mut self, ri: usize, sample: u32, keep: &[u32]) -> bool {
        let frame = self.frame;
        let Some(slot) = self.reflectors[ri].table.reserve(sample, keep, frame) else {
            return false;
        };
        let (class, element) = {
            let r = &self.reflectors[ri];
            (r.class, r.base + slot as u32)
        };
        let maps = self
            .settings
            .layers()
            .iter()
            .enumerate()
            .map(|(li, &layer)| Ok((self.key(ri, layer, sample), self.lend(class, li, element)?)))
            .collect::<Result<Vec<_>>>();
        let job = maps.map(|maps| Job::Slot {
            maps,
            drop: self.settings.drop_levels,
        });
        let sent = match (job, self.prefetch.as_mut()) {
            (Ok(job), Some(p)) => p.request(job).is_none(),
            _ => false,
        };
        if !sent {
            self.reflectors[ri].table.abandon(slot);
        }
        sent
    }

    /// Has the worker decode every layer of `sample` of reflector `ri`
    /// into staging buffers; false when no buffer is left.
    fn prefetch_staging(&mut self, ri: usize, sample: u32) -> bool {
        for layer in self.settings.layers() {
            let key = self.key(ri, layer, sample);
            let Some(prefetch) = self.prefetch.as_mut() else {
                return false;
            };
            if prefetch.has(&key) {
                continue;
            }
            let Ok(buffer) = self.pool.take() else {
                return false;
            };
            if let Some(Job::Staging(_, unused)) = prefetch.request(Job::Staging(key, buffer)) {
                self.pool.give(unused);
            }
        }
        true
    }

    /// The upload pass for what `prepare` read into staging (None when
    /// nothing was: all resident, or decoded straight into the slots).
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
}

/// Each EM resolution class's arrays, one per layer.
pub(super) type Classes = Vec<(u32, Vec<Arc<Image>>)>;

/// The map arrays of every class (`resolutions`: each class's resolution
/// and member reflectors), and whether they are host-written: all or none,
/// where the device can sample every one so and the settings do not ask
/// for staging uploads.
pub(super) fn map_arrays(
    device: &Device,
    settings: &PemSettings,
    resolutions: &[(u32, usize)],
) -> Result<(Classes, bool)> {
    let (layers, drop) = (settings.layers(), settings.drop_levels);
    let elements = |members: usize| (members * SLOTS) as u32;
    let host = !settings.staging_uploads
        && resolutions.iter().all(|&(r, members)| {
            layers.iter().all(|&l| {
                Image::host_writable(device, map_array_desc(l, (r, drop), elements(members)))
            })
        });
    let classes = resolutions
        .iter()
        .map(|&(resolution, members)| {
            let arrays = layers
                .iter()
                .map(|&l| map_array(device, l, (resolution, drop), elements(members), host))
                .collect::<Result<Vec<_>>>()?;
            Ok((resolution, arrays))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((classes, host))
}

/// The array a `layer`'s maps play from: one element per slot of every
/// reflector, RGBA16F, full MIP chain from the level `drop` below the
/// finest of a reflector with `resolution`² EMs; host-written where the
/// device allows (`host`).
fn map_array(
    device: &Device,
    layer: MapLayer,
    (resolution, drop): (u32, u32),
    elements: u32,
    host: bool,
) -> Result<Arc<Image>> {
    let desc = map_array_desc(layer, (resolution, drop), elements);
    let desc = match host {
        true => desc.host_written(),
        false => desc.usage(vk::ImageUsageFlags::TRANSFER_DST),
    };
    Ok(Arc::new(Image::new(
        device,
        &format!("{} maps", layer.file_part()),
        desc,
    )?))
}

/// The description of a map array, without its way of being written.
fn map_array_desc(layer: MapLayer, (resolution, drop): (u32, u32), elements: u32) -> ImageDesc {
    let format = vk::Format::R16G16B16A16_SFLOAT;
    match layer {
        MapLayer::Ptm => {
            let edge = ptm_edge(resolution) >> drop;
            ImageDesc::new_2d_array(format, edge, edge, elements)
        }
        _ => ImageDesc::new_cube_array(format, resolution >> drop, elements),
    }
    .all_mip_levels()
    .usage(vk::ImageUsageFlags::SAMPLED)
}

/// Moves host-written arrays to the layout they are written and sampled
/// in (GENERAL) before any host write: one empty submission.
pub(super) struct MakeHostReadable<'a>(pub Vec<&'a Image>);

impl Pass for MakeHostReadable<'_> {
    fn name(&self) -> &str {
        "host_maps_layout"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.0
            .iter()
            .map(|i| Access::whole(i, Usage::Sampled))
            .collect()
    }
    fn record(&self, _cmd: vk::CommandBuffer) -> GpuResult<()> {
        Ok(())
    }
}

/// Bytes of the `drop` finest levels in the staging layout.
fn dropped_bytes(layer: MapLayer, resolution: u32, drop: u32) -> GpuResult<u64> {
    if drop == 0 {
        return Ok(0);
    }
    // One undropped element: the staging layout of one map.
    let (regions, _) = level_regions(&map_array_desc(layer, (resolution, 0), 1))?;
    Ok(regions.get(drop as usize).map_or(0, |r| r.buffer_offset))
}
