//! The glass pass: the lens's per-frame tessellation (CPU vertex ray
//! paths, `inference::glass`) drawn over the room, each pixel
//! `T·F_T·G_T + R·F_R·G_R` read from the shell cube map, or mixed from
//! two per-sample shell maps of a cube-map array.

use super::target::Target;
use crate::backend::{Binding, Buffer, Device, GpuResult, Pipeline, PipelineDesc, Sampler};
use crate::graph::{Access, Pass};
use crate::shader_interface::{GLASS_ATTRIBUTES, GLASS_BINDING, GlassPush, spirv};
use ash::vk;
use glam::{Mat4, Vec4};

/// The glass pipeline (back faces culled: the CPU emits front faces only)
/// with `fragment` (`glass.frag` or `glass_blend.frag`).
pub fn glass_pipeline(
    device: &Device,
    (name, fragment): (&str, &[u8]),
    color_format: vk::Format,
    depth_format: vk::Format,
) -> GpuResult<Pipeline> {
    Pipeline::new(
        device,
        &PipelineDesc {
            name,
            vertex_spirv: spirv::GLASS_VERT,
            fragment_spirv: fragment,
            vertex_bindings: &[GLASS_BINDING],
            vertex_attributes: &GLASS_ATTRIBUTES,
            color_formats: &[color_format],
            depth_format,
            cull_mode: vk::CullModeFlags::BACK,
            push_constant_size: size_of::<GlassPush>() as u32,
            bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
            blend: crate::backend::Blend::Replace,
            depth: crate::backend::DepthTest::TestWrite,
            stencil: crate::backend::StencilTest::Off,
        },
    )
}

/// The per-frame geometry of the lens: host-visible buffers that grow to
/// the largest tessellation seen (the previous frame's fence has passed
/// before they are rewritten).
pub struct GlassGeometry {
    device: Device,
    formats: (vk::Format, vk::Format),
    pipeline: Pipeline,
    sampler: Sampler,
    set: vk::DescriptorSet,
    /// The blending pipeline and its set over the per-sample maps.
    blend: Option<(Pipeline, vk::DescriptorSet)>,
    vertices: Option<Buffer>,
    indices: Option<Buffer>,
    pub index_count: u32,
}

impl GlassGeometry {
    /// Geometry sampling the cube map `shell`.
    pub fn new(
        device: &Device,
        shell: &crate::backend::Image,
        formats: (vk::Format, vk::Format),
    ) -> GpuResult<Self> {
        let pipeline = glass_pipeline(device, ("glass", spirv::GLASS_FRAG), formats.0, formats.1)?;
        let sampler = Sampler::trilinear(device, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let set = pipeline.descriptor_set(&[Binding::Image(shell.view, sampler.raw)])?;
        Ok(Self {
            device: device.clone(),
            formats,
            pipeline,
            sampler,
            set,
            blend: None,
            vertices: None,
            indices: None,
            index_count: 0,
        })
    }

    /// Makes the blending pipeline, reading the cube-map array `samples`.
    pub fn set_samples(&mut self, samples: &crate::backend::Image) -> GpuResult<()> {
        let (color, depth) = self.formats;
        let names = ("glass blend", spirv::GLASS_BLEND_FRAG);
        let pipeline = glass_pipeline(&self.device, names, color, depth)?;
        let set = pipeline.descriptor_set(&[Binding::Image(samples.view, self.sampler.raw)])?;
        self.blend = Some((pipeline, set));
        Ok(())
    }

    /// Copies a frame's vertex stream and indices into the buffers.
    pub fn upload(&mut self, stream: &[f32], indices: &[u32]) -> GpuResult<()> {
        let device = &self.device;
        fill(
            device,
            &mut self.vertices,
            "glass vertices",
            vk::BufferUsageFlags::VERTEX_BUFFER,
            bytemuck::cast_slice(stream),
        )?;
        fill(
            device,
            &mut self.indices,
            "glass indices",
            vk::BufferUsageFlags::INDEX_BUFFER,
            bytemuck::cast_slice(indices),
        )?;
        self.index_count = indices.len() as u32;
        Ok(())
    }

    /// The pass reading `shell`, or with `samples` (the array given to
    /// [`GlassGeometry::set_samples`] and the blend: layers, weight) those.
    pub fn pass<'a>(
        &'a self,
        shell: &'a crate::backend::Image,
        samples: Option<(&'a crate::backend::Image, Vec4)>,
        target: Target<'a>,
        view_proj: Mat4,
    ) -> GlassPass<'a> {
        GlassPass {
            geometry: self,
            shell,
            samples: samples.filter(|_| self.blend.is_some()),
            target,
            view_proj,
        }
    }
}

/// Writes `bytes` into `slot`, replacing it by a larger buffer (twice the
/// size asked, so growth is rare) when it is too small.
fn fill(
    device: &Device,
    slot: &mut Option<Buffer>,
    name: &str,
    usage: vk::BufferUsageFlags,
    bytes: &[u8],
) -> GpuResult<()> {
    let len = bytes.len() as u64;
    if slot.as_ref().is_none_or(|b| b.size < len) {
        *slot = Some(Buffer::new(
            device,
            name,
            (2 * len).max(1024),
            usage,
            gpu_allocator::MemoryLocation::CpuToGpu,
        )?);
    }
    if let Some(buffer) = slot.as_mut() {
        buffer.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
    }
    Ok(())
}

/// Draws the lens over what the room pass left in the target.
pub struct GlassPass<'a> {
    geometry: &'a GlassGeometry,
    shell: &'a crate::backend::Image,
    samples: Option<(&'a crate::backend::Image, Vec4)>,
    target: Target<'a>,
    view_proj: Mat4,
}

impl Pass for GlassPass<'_> {
    fn name(&self) -> &str {
        "glass"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        match self.samples {
            Some((samples, _)) => self.target.accesses(&[samples]),
            None => self.target.accesses(&[self.shell]),
        }
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let g = self.geometry;
        self.target.render(&g.device, cmd, || {
            let (Some(vertices), Some(indices)) = (&g.vertices, &g.indices) else {
                return Ok(());
            };
            if g.index_count == 0 {
                return Ok(());
            }
            let (pipeline, set, blend) = match (self.samples, &g.blend) {
                (Some((_, blend)), Some((pipeline, set))) => (pipeline, *set, blend),
                _ => (&g.pipeline, g.set, Vec4::ZERO),
            };
            let push = GlassPush {
                view_proj: self.view_proj,
                blend,
            };
            pipeline.bind(cmd, Some(set), &push)?;
            // SAFETY: the glass pipeline is bound inside dynamic rendering;
            // the buffers hold index_count indices into the uploaded vertices.
            unsafe {
                let d = &g.device.device;
                d.cmd_bind_vertex_buffers(cmd, 0, &[vertices.raw], &[0]);
                d.cmd_bind_index_buffer(cmd, indices.raw, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cmd, g.index_count, 1, 0, 0, 0);
            }
            Ok(())
        })
    }
}
