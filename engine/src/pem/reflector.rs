//! One reflector as PEM playback sees it: its EM geometries and origin,
//! its indices with convex-hull triangles first, its per-frame texgen
//! streams, and its resident sample slots (images and descriptor sets).

use super::residency::{SLOTS, SlotTable};
use super::settings::{PemKind, PemSettings};
use super::source::MapLayer;
use crate::backend::{Binding, Buffer, Device, Image, ImageDesc, Sampler};
use crate::passes::pem::{PemPipelines, Shading};
use anyhow::{Result, bail};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use inference::em_geometry::{EmGeometry, bounding_ellipsoid, texgen};
use inference::scene::{Object, Scene};
use inference::texgen::TexgenVertex;

/// One resident sample's maps and the descriptor sets that sample them.
pub struct Slot {
    pub images: Vec<Image>,
    /// Binds every layer (+ the LUT for EMs).
    pub set: vk::DescriptorSet,
    /// Layered PEMs: the distant layer alone, for hull triangles.
    pub hull_set: Option<vk::DescriptorSet>,
}

/// The samplers and LUT every slot's descriptor sets bind.
pub struct SlotBindings<'a> {
    pub pipelines: &'a PemPipelines,
    pub lut: &'a Image,
    pub cube: &'a Sampler,
    pub flat: &'a Sampler,
}

pub struct PemReflector {
    /// Index of the object in the scene (and its GPU mesh).
    pub object: usize,
    pub name: String,
    pub f0: Vec3,
    pub resolution: u32,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    origin: Vec3,
    /// World-space bounds: what the draw passes' render area must cover.
    pub bounds: (Vec3, Vec3),
    distant: EmGeometry,
    local: EmGeometry,
    /// Triangles on the convex hull first, then the rest.
    pub indices: Buffer,
    pub hull_index_count: u32,
    pub index_count: u32,
    pub texgen_distant: Buffer,
    pub texgen_local: Buffer,
    pub slots: Vec<Slot>,
    pub table: SlotTable,
}

impl PemReflector {
    pub fn new(
        device: &Device,
        scene: &Scene,
        (object, o): (usize, &Object),
        f0: Vec3,
        settings: &PemSettings,
        bindings: &SlotBindings,
    ) -> Result<Self> {
        let resolution = o.em.as_ref().map_or(1, |em| em.resolution.max(1));
        if settings.drop_levels >= 32 - resolution.leading_zeros() {
            bail!(
                "{}: dropping {} MIP levels of a {resolution}² map leaves none",
                o.name,
                settings.drop_levels
            );
        }
        let (room_min, room_max) = scene.bounds();
        let origin = o.mesh.area_weighted_centroid();
        // Convex-hull triangles cannot see the reflector: distant EM only.
        let hull = inference::hull::hull_triangles(&o.mesh);
        let (indices, hull_index_count) = hull_sorted_indices(&o.mesh.indices, &hull);
        let stream = |name: &str| {
            Buffer::new(
                device,
                &format!("{} {name}", o.name),
                (o.mesh.positions.len() * size_of::<TexgenVertex>()) as u64,
                vk::BufferUsageFlags::VERTEX_BUFFER,
                MemoryLocation::CpuToGpu,
            )
        };
        let mut r = PemReflector {
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
            table: SlotTable::new(SLOTS),
        };
        for _ in 0..SLOTS {
            let slot = r.make_slot(device, settings, bindings)?;
            r.slots.push(slot);
        }
        Ok(r)
    }

    /// CPU texgen for `eye` into the streams `settings` draw with (`scratch`
    /// is reused between calls).
    pub fn texgen(
        &mut self,
        eye: Vec3,
        settings: &PemSettings,
        scratch: &mut Vec<TexgenVertex>,
    ) -> Result<()> {
        if settings.kind == PemKind::Ptm {
            return Ok(());
        }
        scratch.resize(self.positions.len(), [0.0; 4]);
        let first = match settings.kind {
            PemKind::Sphere => EmGeometry::SphereAtInfinity,
            _ => self.distant,
        };
        let mut streams = vec![(first, &mut self.texgen_distant)];
        if settings.kind == PemKind::Layered && settings.local_layer {
            streams.push((self.local, &mut self.texgen_local));
        }
        for (geometry, buffer) in streams {
            texgen(
                &geometry,
                self.origin,
                eye,
                &self.positions,
                &self.normals,
                scratch,
            );
            let bytes: &[u8] = bytemuck::cast_slice(scratch);
            buffer.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        }
        Ok(())
    }

    /// The images of one sample slot and its descriptor sets.
    fn make_slot(&self, device: &Device, settings: &PemSettings, b: &SlotBindings) -> Result<Slot> {
        let size = self.resolution >> settings.drop_levels;
        let layers = settings.layers();
        let mut images = Vec::new();
        for layer in &layers {
            let desc = map_desc(*layer, size)
                .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
            images.push(Image::new(
                device,
                &format!("{} {} slot", self.name, layer.file_part()),
                desc,
            )?);
        }
        let lut = Binding::Image(b.lut.view, b.cube.raw);
        let cube = |i: usize| Binding::Image(images[i].view, b.cube.raw);
        let single = |i| {
            b.pipelines
                .get(Shading::SingleEm, false)
                .descriptor_set(&[cube(i), lut])
        };
        let (set, hull_set) = match settings.kind {
            PemKind::Layered if layers.len() == 2 => (
                b.pipelines.get(Shading::Layered, false).descriptor_set(&[
                    cube(0),
                    cube(1),
                    lut,
                ])?,
                Some(single(0)?),
            ),
            PemKind::Ptm => (
                b.pipelines
                    .get(Shading::Ptm, false)
                    .descriptor_set(&[Binding::Image(images[0].view, b.flat.raw)])?,
                None,
            ),
            _ => (single(0)?, None),
        };
        Ok(Slot {
            images,
            set,
            hull_set,
        })
    }
}

/// The image a `size` map of `layer` plays from: RGBA16F, full MIP chain.
pub fn map_desc(layer: MapLayer, size: u32) -> ImageDesc {
    let format = vk::Format::R16G16B16A16_SFLOAT;
    match layer {
        MapLayer::Ptm => ImageDesc::new_2d(format, size, size),
        _ => ImageDesc::new_cube(format, size),
    }
    .all_mip_levels()
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
