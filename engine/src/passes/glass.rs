//! The glass pass: the lens's per-frame tessellation (CPU vertex ray
//! paths, `inference::glass`) drawn over the room, each pixel
//! `T·F_T·G_T + R·F_R·G_R` read from the shell cube map, mixed from two
//! per-sample shell maps of a cube-map array, or composited from layered
//! shells (one array element per layer, nearest first).

use super::glass_deferred::{DeferredGlass, DeferredLens};
use super::target::{AroundRoom, Load, Target};
use crate::backend::{Binding, Buffer, Device, GpuResult, Pipeline, PipelineDesc, Sampler};
use crate::graph::{Access, Pass};
use crate::shader_interface::{
    GLASS_ATTRIBUTES, GLASS_BINDING, GLASS_LAYERS_ATTRIBUTES, GLASS_LAYERS_BINDING,
    GLASS_OUTER_ATTRIBUTES, GlassPush, spirv,
};
use ash::vk;
use glam::{Mat4, Vec4};

/// What a glass pipeline reads of which vertex stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// The one-shell stream, `glass.vert`.
    OneShell,
    /// The layered stream, every shell's lookups (`glass_layers.vert`).
    Layered,
    /// The layered stream, the outermost shell's lookups (`glass.vert`).
    Outermost,
}

/// The glass pipeline (back faces culled: the CPU emits front faces only)
/// with `fragment` over `stream`: `glass.frag` or `glass_blend.frag` over
/// the one-shell stream, `glass_layers.frag` over every layer,
/// `glass_layer.frag` over the outermost; `blend` sets the layered
/// shaders' constant (per-sample layer maps).
pub fn glass_pipeline(
    device: &Device,
    (name, fragment): (&str, &[u8]),
    (stream, blend): (Stream, bool),
    (color_format, depth_format): (vk::Format, vk::Format),
) -> GpuResult<Pipeline> {
    let (vertex_spirv, binding, attributes): (_, _, &[_]) = match stream {
        Stream::Layered => (
            spirv::GLASS_LAYERS_VERT,
            GLASS_LAYERS_BINDING,
            &GLASS_LAYERS_ATTRIBUTES,
        ),
        Stream::Outermost => (
            spirv::GLASS_VERT,
            GLASS_LAYERS_BINDING,
            &GLASS_OUTER_ATTRIBUTES,
        ),
        Stream::OneShell => (spirv::GLASS_VERT, GLASS_BINDING, &GLASS_ATTRIBUTES),
    };
    let variants: &[u32] = if blend { &[1] } else { &[] };
    Pipeline::with_variants(
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
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_constant_size: size_of::<GlassPush>() as u32,
            bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
            blend: crate::backend::Blend::Replace,
            depth: crate::backend::DepthTest::TestWrite,
            stencil: crate::backend::StencilTest::Off,
        },
        variants,
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
    /// The deferred passes over the per-sample maps.
    deferred: Option<DeferredGlass>,
    /// Over the layer maps: the pipeline reading every layer, the one
    /// reading the outermost, and their sets.
    layers: Option<[(Pipeline, vk::DescriptorSet); 2]>,
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
        let names = ("glass", spirv::GLASS_FRAG);
        let pipeline = glass_pipeline(device, names, (Stream::OneShell, false), formats)?;
        let sampler = Sampler::trilinear(device, vk::SamplerAddressMode::CLAMP_TO_EDGE)?;
        let set = pipeline.descriptor_set(&[Binding::Image(shell.view, sampler.raw)])?;
        Ok(Self {
            device: device.clone(),
            formats,
            pipeline,
            sampler,
            set,
            blend: None,
            deferred: None,
            layers: None,
            vertices: None,
            indices: None,
            index_count: 0,
        })
    }

    /// Makes the blending pipeline reading the cube-map array `samples`,
    /// and with a frame size the deferred passes (their G-buffer at that
    /// size); both or, on an error, neither.
    pub fn set_samples(
        &mut self,
        samples: &crate::backend::Image,
        deferred: Option<(u32, u32)>,
    ) -> GpuResult<()> {
        let names = ("glass blend", spirv::GLASS_BLEND_FRAG);
        let pipeline =
            glass_pipeline(&self.device, names, (Stream::OneShell, false), self.formats)?;
        let set = pipeline.descriptor_set(&[Binding::Image(samples.view, self.sampler.raw)])?;
        let make =
            |size| DeferredGlass::new(&self.device, samples, &self.sampler, self.formats, size);
        let deferred = deferred.map(make).transpose()?;
        self.blend = Some((pipeline, set));
        self.deferred = deferred;
        Ok(())
    }

    /// Whether per-sample maps draw deferred (they were set with a frame
    /// size).
    pub fn deferred(&self) -> bool {
        self.deferred.is_some()
    }

    /// Drops the pipelines, sets and G-buffer over per-sample maps and
    /// layers (their images are being let go).
    pub fn clear_samples(&mut self) {
        self.blend = None;
        self.deferred = None;
        self.layers = None;
    }

    /// Makes the layered pipelines, reading the cube-map array `layers`
    /// (with `blend`, per-sample layer maps mixed two by two).
    pub fn set_layers(&mut self, layers: &crate::backend::Image, blend: bool) -> GpuResult<()> {
        let make = |names, stream| -> GpuResult<(Pipeline, vk::DescriptorSet)> {
            let pipeline = glass_pipeline(&self.device, names, (stream, blend), self.formats)?;
            let set = pipeline.descriptor_set(&[Binding::Image(layers.view, self.sampler.raw)])?;
            Ok((pipeline, set))
        };
        self.layers = Some([
            make(("glass layers", spirv::GLASS_LAYERS_FRAG), Stream::Layered)?,
            make(
                ("glass outer layer", spirv::GLASS_LAYER_FRAG),
                Stream::Outermost,
            )?,
        ]);
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

    /// The passes reading `source`'s maps (the arrays given to
    /// [`GlassGeometry::set_samples`] or [`GlassGeometry::set_layers`]):
    /// per-sample maps, where they were set deferred, as a G-buffer and a
    /// composite inside `bands` (the composite's scissors; empty: the
    /// render area), anything else as one forward pass after the room.
    /// With `first` (nothing else lays the frame's depth before the room)
    /// the deferred G-buffer pass goes before the room and clears depth.
    pub fn passes<'a>(
        &'a self,
        source: ShellSource<'a>,
        target: Target<'a>,
        view_proj: Mat4,
        (bands, first): (&'a [vk::Rect2D], bool),
    ) -> AroundRoom<'a> {
        if let (ShellSource::Samples(samples, blend), Some(glass)) = (source, &self.deferred)
            && let (Some(vertices), Some(indices)) = (&self.vertices, &self.indices)
        {
            // No lens this frame: no G-buffer, and no composite over the
            // whole area for a stencil that marks nothing.
            if self.index_count == 0 {
                return AroundRoom::after_room(Vec::new());
            }
            let lens = DeferredLens {
                vertices,
                indices,
                index_count: self.index_count,
                bands,
            };
            let [gbuffer, composite] =
                glass.passes(lens, target, (view_proj, blend), samples, first);
            return match first {
                true => AroundRoom {
                    before_room: vec![gbuffer],
                    room_load: Load::ClearColor,
                    after_room: vec![composite],
                },
                false => AroundRoom::after_room(vec![gbuffer, composite]),
            };
        }
        AroundRoom::after_room(vec![Box::new(GlassPass {
            geometry: self,
            source,
            target,
            view_proj,
        })])
    }

    /// Each draw of `source`: pipeline, set, push `blend`, first index and
    /// index count — one over every triangle, or for layers the leading
    /// triangles reading every layer, then the rest reading the outermost
    /// (the one map when the source's pipelines are missing).
    fn draws(&self, source: &ShellSource) -> Vec<(&Pipeline, vk::DescriptorSet, Vec4, u32, u32)> {
        let total = self.index_count;
        match (source, &self.blend, &self.layers) {
            (ShellSource::Samples(_, blend), Some((p, set)), _) => {
                vec![(p, *set, *blend, 0, total)]
            }
            (ShellSource::Layers(_, blend, lead), _, Some([every, outer])) => {
                let (lead, blend) = ((*lead).min(total), *blend);
                [(every, 0, lead), (outer, lead, total - lead)]
                    .into_iter()
                    .filter(|d| d.2 > 0)
                    .map(|((p, set), first, count)| (p, *set, blend, first, count))
                    .collect()
            }
            _ => vec![(&self.pipeline, self.set, Vec4::ZERO, 0, total)],
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
    /// Layer maps (nearest first; per sample, sample after sample), the
    /// layered shaders' push (layers, the two samples' first elements,
    /// the weight of the second) and how many indices lead with triangles
    /// that read every layer (the rest read the outermost alone).
    Layers(&'a crate::backend::Image, Vec4, u32),
}

impl ShellSource<'_> {
    fn image(&self) -> &crate::backend::Image {
        match self {
            ShellSource::One(i) | ShellSource::Samples(i, _) | ShellSource::Layers(i, ..) => i,
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
            for (pipeline, set, blend, first, count) in g.draws(&self.source) {
                let push = GlassPush {
                    view_proj: self.view_proj,
                    blend,
                };
                pipeline.bind(cmd, Some(set), &push)?;
                // SAFETY: the glass pipeline is bound inside dynamic
                // rendering; `draws` keeps first + count within the
                // index_count indices into the uploaded vertices, whose
                // stream is the one the pipeline reads (layered or not).
                unsafe {
                    let d = &g.device.device;
                    d.cmd_bind_vertex_buffers(cmd, 0, &[vertices.raw], &[0]);
                    d.cmd_bind_index_buffer(cmd, indices.raw, 0, vk::IndexType::UINT32);
                    d.cmd_draw_indexed(cmd, count, 1, first, 0, 0);
                }
            }
            Ok(())
        })
    }
}
