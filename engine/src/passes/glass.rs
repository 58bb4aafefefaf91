//! The glass pass: the lens's per-frame tessellation (CPU vertex ray
//! paths, `inference::glass`) drawn over the room, each pixel
//! `T·F_T·G_T + R·F_R·G_R` read from the shell cube map, mixed from two
//! per-sample shell maps of a cube-map array, or composited from layered
//! shells (one array element per layer, nearest first).

use super::target::Target;
use crate::backend::{Binding, Buffer, Device, GpuResult, Pipeline, PipelineDesc, Sampler};
use crate::graph::{Access, Pass};
use crate::shader_interface::{
    GLASS_ATTRIBUTES, GLASS_BINDING, GLASS_LAYERS_ATTRIBUTES, GLASS_LAYERS_BINDING, GlassPush,
    spirv,
};
use ash::vk;
use glam::{Mat4, Vec4};

/// The glass pipeline (back faces culled: the CPU emits front faces only)
/// with `fragment` (`glass.frag` or `glass_blend.frag` over the one-shell
/// stream; with `layered`, `glass_layers.*` over the layered stream).
pub fn glass_pipeline(
    device: &Device,
    (name, fragment): (&str, &[u8]),
    layered: bool,
    (color_format, depth_format): (vk::Format, vk::Format),
) -> GpuResult<Pipeline> {
    let (vertex_spirv, binding, attributes): (_, _, &[_]) = match layered {
        true => (
            spirv::GLASS_LAYERS_VERT,
            GLASS_LAYERS_BINDING,
            &GLASS_LAYERS_ATTRIBUTES,
        ),
        false => (spirv::GLASS_VERT, GLASS_BINDING, &GLASS_ATTRIBUTES),
    };
    Pipeline::new(
        device,
        &PipelineDesc {
            name,
            vertex_spirv,
            fragment_spirv: fragment,
            vertex_bindings: &[binding],
            vertex_attributes: attributes,
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
    /// The layered pipeline and its set over the layer maps.
    layers: Option<(Pipeline, vk::DescriptorSet)>,
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
        let pipeline = glass_pipeline(device, ("glass", spirv::GLASS_FRAG), false, formats)?;
        let sampler = Sampler::trilinear(device, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let set = pipeline.descriptor_set(&[Binding::Image(shell.view, sampler.raw)])?;
        Ok(Self {
            device: device.clone(),
            formats,
            pipeline,
            sampler,
            set,
            blend: None,
            layers: None,
            vertices: None,
            indices: None,
            index_count: 0,
        })
    }

    /// Makes the blending pipeline, reading the cube-map array `samples`.
    pub fn set_samples(&mut self, samples: &crate::backend::Image) -> GpuResult<()> {
        let names = ("glass blend", spirv::GLASS_BLEND_FRAG);
        let pipeline = glass_pipeline(&self.device, names, false, self.formats)?;
        let set = pipeline.descriptor_set(&[Binding::Image(samples.view, self.sampler.raw)])?;
        self.blend = Some((pipeline, set));
        Ok(())
    }

    /// Makes the layered pipeline, reading the cube-map array `layers`.
    pub fn set_layers(&mut self, layers: &crate::backend::Image) -> GpuResult<()> {
        let names = ("glass layers", spirv::GLASS_LAYERS_FRAG);
        let pipeline = glass_pipeline(&self.device, names, true, self.formats)?;
        let set = pipeline.descriptor_set(&[Binding::Image(layers.view, self.sampler.raw)])?;
        self.layers = Some((pipeline, set));
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

    /// The pass reading `source`'s maps (the arrays given to
    /// [`GlassGeometry::set_samples`] or [`GlassGeometry::set_layers`]).
    pub fn pass<'a>(
        &'a self,
        source: ShellSource<'a>,
        target: Target<'a>,
        view_proj: Mat4,
    ) -> GlassPass<'a> {
        GlassPass {
            geometry: self,
            source,
            target,
            view_proj,
        }
    }

    /// The pipeline, its set and the push constants' `blend` for `source`
    /// (the one map when its pipeline is missing).
    fn pipeline_for(&self, source: &ShellSource) -> (&Pipeline, vk::DescriptorSet, Vec4) {
        match (source, &self.blend, &self.layers) {
            (ShellSource::Samples(_, blend), Some((p, set)), _) => (p, *set, *blend),
            (ShellSource::Layers(_, n), _, Some((p, set))) => {
                (p, *set, Vec4::new(*n as f32, 0.0, 0.0, 0.0))
            }
            _ => (&self.pipeline, self.set, Vec4::ZERO),
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

/// Which maps a glass pass reads.
#[derive(Clone, Copy)]
pub enum ShellSource<'a> {
    /// The one shell map.
    One(&'a crate::backend::Image),
    /// Per-sample maps and the blend (layers, weight of the second).
    Samples(&'a crate::backend::Image, Vec4),
    /// Layer maps, nearest first, and how many layers.
    Layers(&'a crate::backend::Image, u32),
}

impl ShellSource<'_> {
    fn image(&self) -> &crate::backend::Image {
        match self {
            ShellSource::One(i) | ShellSource::Samples(i, _) | ShellSource::Layers(i, _) => i,
        }
    }
}

/// Draws the lens over what the room pass left in the target.
pub struct GlassPass<'a> {
    geometry: &'a GlassGeometry,
    source: ShellSource<'a>,
    target: Target<'a>,
    view_proj: Mat4,
}

impl Pass for GlassPass<'_> {
    fn name(&self) -> &str {
        "glass"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.target.accesses(&[self.source.image()])
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
            let (pipeline, set, blend) = g.pipeline_for(&self.source);
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
