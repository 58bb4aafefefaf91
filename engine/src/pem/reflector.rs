//! One reflector as PEM playback sees it: its EM geometries and origin,
//! its indices with convex-hull triangles first (per frame, those that may
//! face the eye), its per-frame texgen streams, and which samples its
//! slots hold (the slots themselves are elements of the player's map
//! arrays, from `base` on).

use super::ahead::{ScreenParts, TexgenFrame, TexgenInputs, TexgenRequest};
use super::facing::FacingMesh;
use super::residency::{SLOTS, SlotTable};
use super::settings::{PemKind, PemSettings};
use crate::backend::{Buffer, Device};
use crate::gpu_scene::GpuMesh;
use crate::maps::ptm_edge;
use crate::passes::outline::MeshEdges;
use anyhow::{Result, bail};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use inference::em_geometry::{EmGeometry, bounding_ellipsoid};
use inference::scene::{Object, Scene};
use inference::texgen::TexgenVertex;

pub struct PemReflector {
    /// Index of the object in the scene (and its GPU mesh).
    pub object: usize,
    pub name: String,
    pub f0: Vec3,
    pub resolution: u32,
    /// Added to every map lookup's level of detail (`[objects.em] lod_bias`,
    /// as the maps were inferred).
    pub lod_bias: f32,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// The mesh's triangles (the outline's edges index them).
    triangles: Vec<u32>,
    /// The hull-sorted triangles, of which each frame keeps those that may
    /// face its eye.
    facing: FacingMesh,
    /// Its edges and the triangles beside them (the outline's tiles): only
    /// with the edge filter, which alone reads them (~6 ms to build for
    /// the teapot).
    edges: Option<MeshEdges>,
    /// The compositing pass's scissor bands and the edge filter's outline
    /// tiles for the frame texgen last ran for (empty: draw the bounding
    /// rectangle).
    screen: ScreenParts,
    origin: Vec3,
    /// World-space bounds: what the draw passes' render area must cover.
    pub bounds: (Vec3, Vec3),
    distant: EmGeometry,
    local: EmGeometry,
    /// The triangles the frame texgen last ran for draws (those that may
    /// face its eye): on the convex hull first, then the rest.
    pub indices: Buffer,
    pub hull_index_count: u32,
    pub index_count: u32,
    pub texgen_distant: Buffer,
    pub texgen_local: Buffer,
    /// The mesh on its PTM atlas (`inference::atlas`), when PTMs play.
    pub ptm_mesh: Option<GpuMesh>,
    pub table: SlotTable,
    /// Its map class (EM resolution) in the frame's sets.
    pub class: usize,
    /// The array element of this reflector's slot 0 in its class's arrays.
    pub base: u32,
    /// The next frame's texgen and bands, computed while this one rendered.
    ahead: Option<TexgenFrame>,
}

impl PemReflector {
    pub fn new(
        device: &Device,
        scene: &Scene,
        (object, o): (usize, &Object),
        f0: Vec3,
        settings: &PemSettings,
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
        // Convex-hull triangles cannot see the reflector (nor the parts
        // sharing its local layer): distant EM only.
        let others: Vec<&inference::scene::Mesh> = (scene.local_group(object).into_iter())
            .filter(|&i| i != object)
            .filter_map(|i| scene.objects.get(i).map(|p| &p.mesh))
            .collect();
        let hull = inference::hull::hull_triangles_among(&o.mesh, &others);
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
        let ptm_mesh = (settings.kind == PemKind::Ptm)
            .then(|| {
                let atlas = inference::atlas::build(&o.mesh, ptm_edge(resolution)).mesh(&o.mesh);
                GpuMesh::upload(device, &format!("{} PTM atlas", o.name), &atlas)
            })
            .transpose()?;
        Ok(PemReflector {
            object,
            name: o.name.clone(),
            f0,
            resolution,
            lod_bias: o.lod_bias(),
            positions: o.mesh.positions.clone(),
            normals: o.mesh.normals.clone(),
            triangles: o.mesh.indices.clone(),
            facing: FacingMesh::new(o.mesh.positions.len(), indices.clone(), hull_index_count),
            edges: (settings.edge_filter && settings.deferred())
                .then(|| MeshEdges::new(&o.mesh.positions, &o.mesh.indices)),
            screen: ScreenParts::default(),
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
            ptm_mesh,
            table: SlotTable::new(SLOTS),
            // Set when the player groups the reflectors by resolution.
            class: 0,
            base: 0,
            ahead: None,
        })
    }

    /// The rows this reflector covers in the frame texgen last ran for,
    /// as scissor bands inside `within` ([`super::bands`]); empty where no
    /// bound holds (a vertex behind the eye: draw `within`).
    pub fn bands(&self, within: vk::Rect2D) -> Vec<vk::Rect2D> {
        crate::passes::bands::clipped(&self.screen.bands, within)
    }

    /// The tiles this reflector's outline can reach in the frame texgen
    /// last ran for ([`crate::passes::outline`]): the whole frame where no
    /// bound holds (a vertex behind the eye), none with the filter off.
    pub fn outline(&self) -> &[vk::Rect2D] {
        &self.screen.outline
    }

    /// The array element holding `sample`, if it is resident (not still
    /// being filled ahead).
    pub fn element(&self, sample: u32) -> Option<u32> {
        let slot = self
            .table
            .find(sample)
            .filter(|&s| !self.table.filling(s))?;
        Some(self.base + slot as u32)
    }

    /// What this reflector's texgen reads, for a worker computing the
    /// next frame's ([`super::ahead`]).
    pub fn inputs(&self) -> TexgenInputs<'_> {
        TexgenInputs {
            positions: &self.positions,
            normals: &self.normals,
            triangles: &self.triangles,
            facing: &self.facing,
            edges: self.edges.as_ref(),
            origin: self.origin,
            distant: self.distant,
            local: self.local,
        }
    }

    /// Keeps `frame` (computed ahead) for the frame it was made for.
    pub fn set_ahead(&mut self, frame: TexgenFrame) {
        self.ahead = Some(frame);
    }

    /// CPU texgen for `request` into the streams its settings draw with,
    /// and the compositing bands of its frame — computed now, or copied
    /// from what a worker computed ahead for exactly this request (then
    /// it returns true).
    pub fn texgen(&mut self, request: TexgenRequest) -> Result<bool> {
        let ahead = self.ahead.take().filter(|a| a.request == request);
        let served = ahead.is_some();
        let frame = ahead.unwrap_or_else(|| self.inputs().compute(request));
        let buffers = [&mut self.texgen_distant, &mut self.texgen_local];
        for (stream, buffer) in frame.streams.iter().zip(buffers) {
            let bytes: &[u8] = bytemuck::cast_slice(stream);
            buffer.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        }
        // At most every triangle: the buffer holds them all.
        let bytes: &[u8] = bytemuck::cast_slice(&frame.facing.indices);
        self.indices.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        self.hull_index_count = frame.facing.hull_index_count;
        self.index_count = frame.facing.indices.len() as u32;
        self.screen = frame.screen;
        Ok(served)
    }
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
