//! Deferred PEM compositing (the default): the reflectors are rasterized
//! once into a G-buffer of per-pixel lookups (each layer's cube lookup with
//! its level of detail, and the Fresnel cosine) while the stencil marks
//! their pixels; then one screen pass per reflector part shades only those
//! pixels, once each, reading every layer of every blended sample. The
//! frame's cost no longer grows with the 2×2-quad overdraw of small
//! triangles times the number of samples blended.

use super::target::{Target, render_into, union};
use crate::backend::{
    Buffer, DepthTest, Device, GpuError, GpuResult, Image, ImageDesc, Pipeline, PipelineDesc,
    StencilTest,
};
use crate::gpu_scene::GpuMesh;
use crate::graph::{Access, Pass, Usage};
use crate::shader_interface::{
    CompositePush, LOCAL_TEXGEN_BINDING, PEM_ATTRIBUTES, PemPush, TEXGEN_BINDING, Vertex, spirv,
};
use ash::vk;
use glam::{Mat4, Vec4};

/// What the G-buffer holds where no reflector was drawn: the cosine's
/// sentinel (below any cosine) lets a read-back count covered pixels; the
/// lookups are left undefined (the composite reads only marked pixels, and
/// clearing two RGBA32F frames would cost every frame).
pub const GBUFFER_CLEAR: [Option<[f32; 4]>; 3] = [None, None, Some([-2.0, 0.0, 0.0, 0.0])];

/// G-buffer formats: distant lookup + LOD, local lookup + LOD, cos θ.
pub const GBUFFER_FORMATS: [vk::Format; 3] = [
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32_SFLOAT,
];

/// The per-pixel lookup data of one frame, at the frame's size.
pub struct GBuffer {
    pub images: [Image; 3],
}

impl GBuffer {
    pub fn new(device: &Device, width: u32, height: u32) -> GpuResult<Self> {
        let make = |name: &str, format| {
            Image::new(
                device,
                name,
                ImageDesc::new_2d(format, width, height)
                    // TRANSFER_SRC: the bench reads the coverage back.
                    .usage(
                        vk::ImageUsageFlags::COLOR_ATTACHMENT
                            | vk::ImageUsageFlags::SAMPLED
                            | vk::ImageUsageFlags::TRANSFER_SRC,
                    ),
            )
        };
        Ok(Self {
            images: [
                make("g-buffer distant", GBUFFER_FORMATS[0])?,
                make("g-buffer local", GBUFFER_FORMATS[1])?,
                make("g-buffer cos", GBUFFER_FORMATS[2])?,
            ],
        })
    }
}

/// The composite's variants: how many samples each blends (its shader's
/// `SAMPLES`); variant `i` blends `COMPOSITE_SAMPLES[i]`.
pub const COMPOSITE_SAMPLES: [u32; 4] = [1, 2, 3, 4];

/// The pipelines of deferred compositing: the G-buffer, the reflectors'
/// insides into it, and the composite (one variant per sample count).
pub struct DeferredPipelines {
    pub gbuffer: Pipeline,
    pub interior: Pipeline,
    pub composite: Pipeline,
}

impl DeferredPipelines {
    pub fn new(device: &Device, color: vk::Format, depth: vk::Format) -> GpuResult<Self> {
        let sampler = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let gbuffer = Pipeline::new(
            device,
            &PipelineDesc {
                name: "pem g-buffer",
                vertex_spirv: spirv::PEM_VERT,
                fragment_spirv: spirv::PEM_GBUFFER_FRAG,
                vertex_bindings: &[Vertex::BINDING, TEXGEN_BINDING, LOCAL_TEXGEN_BINDING],
                vertex_attributes: &PEM_ATTRIBUTES,
                color_formats: &GBUFFER_FORMATS,
                depth_format: depth,
                cull_mode: vk::CullModeFlags::BACK,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                push_constant_size: size_of::<PemPush>() as u32,
                bindings: &[sampler; 2],
                blend: crate::backend::Blend::Replace,
                depth: DepthTest::TestWrite,
                stencil: StencilTest::Mark,
            },
        )?;
        // The insides: the stencil unmarked (a part behind an opening had
        // marked it) and the cosine saying "nothing drawn"
        // (pem_gbuffer_interior.frag).
        let interior = super::interior::interior_pipeline(
            device,
            ("pem g-buffer interior", spirv::PEM_GBUFFER_INTERIOR_FRAG),
            &GBUFFER_FORMATS,
            depth,
            StencilTest::Unmark,
        )?;
        let composite = Pipeline::with_variants(
            device,
            &PipelineDesc {
                name: "pem composite",
                vertex_spirv: spirv::PEM_COMPOSITE_VERT,
                fragment_spirv: spirv::PEM_COMPOSITE_FRAG,
                vertex_bindings: &[],
                vertex_attributes: &[],
                color_formats: &[color],
                depth_format: depth,
                cull_mode: vk::CullModeFlags::NONE,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                push_constant_size: size_of::<CompositePush>() as u32,
                bindings: &[sampler; 6],
                blend: crate::backend::Blend::Replace,
                depth: DepthTest::Off,
                stencil: StencilTest::Equal,
            },
            &COMPOSITE_SAMPLES,
        )?;
        Ok(Self {
            gbuffer,
            interior,
            composite,
        })
    }
}

/// A range of a reflector's triangles written into the G-buffer with
/// stencil `stencil` (the reflector's mark); `local` is false on its
/// convex-hull triangles, which see only the distant layer.
pub struct GBufferDraw<'a> {
    pub mesh: &'a GpuMesh,
    pub indices: &'a Buffer,
    pub first_index: u32,
    pub index_count: u32,
    pub texgen: (&'a Buffer, &'a Buffer),
    pub stencil: u32,
    pub local: bool,
    /// The reflector's inside: `mesh` is its caps, drawn with the interior
    /// pipeline (no set, no mark).
    pub interior: bool,
    /// The reflector's LOD bias, added to the recorded levels of detail.
    pub lod_bias: f32,
    /// Binds the distant and local map arrays of the reflector's EM
    /// resolution (for the LOD queries).
    pub set: vk::DescriptorSet,
}

/// Pass 1, the frame's first: the reflectors into the G-buffer, their
/// parts marked in the stencil, their depth laid down for the room.
pub struct GBufferPass<'a> {
    pub device: &'a Device,
    pub pipeline: &'a Pipeline,
    /// For the draws of reflectors' insides.
    pub interior: &'a Pipeline,
    pub gbuffer: &'a GBuffer,
    /// The frame's depth/stencil (cleared by this pass).
    pub depth: &'a Image,
    pub draws: Vec<GBufferDraw<'a>>,
    pub sampled: Vec<&'a Image>,
    pub view_proj: Mat4,
}

impl Pass for GBufferPass<'_> {
    fn name(&self) -> &str {
        "pem_gbuffer"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        let mut a: Vec<Access> = self
            .gbuffer
            .images
            .iter()
            .map(|i| Access::whole(i, Usage::ColorTarget))
            .collect();
        a.push(Access::whole(self.depth, Usage::DepthTarget));
        a.extend(
            self.sampled
                .iter()
                .map(|i| Access::whole(i, Usage::Sampled)),
        );
        a
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let colors: Vec<&Image> = self.gbuffer.images.iter().collect();
        let attachments = Attachments {
            colors: &colors,
            // The frame's first pass: it clears depth and stencil over the
            // whole frame, so the room drawn next skips the reflectors'
            // pixels.
            load: ColorLoad::Clear(&GBUFFER_CLEAR),
            depth: self.depth,
            depth_usage: Usage::DepthTarget,
            clear_depth: true,
            area: None,
        };
        attachments.render(self.device, cmd, || {
            let d = &self.device.device;
            for draw in self.draws.iter().filter(|d| d.index_count > 0) {
                // slot.y: whether this part records a local-layer lookup.
                let push = PemPush {
                    view_proj: self.view_proj,
                    slot: Vec4::new(0.0, f32::from(draw.local), draw.lod_bias, 0.0),
                    ..PemPush::default()
                };
                match draw.interior {
                    true => self.interior.bind(cmd, None, &push)?,
                    false => self.pipeline.bind(cmd, Some(draw.set), &push)?,
                }
                // SAFETY: the G-buffer pipeline (position + two texgen
                // streams) or the interior one (position) is bound inside
                // dynamic rendering; the index range lies within `indices`,
                // whose entries index the mesh (and, for the reflector
                // itself, both streams: one entry per vertex).
                unsafe {
                    // The interior pipeline unmarks (no reference to set).
                    if !draw.interior {
                        d.cmd_set_stencil_reference(
                            cmd,
                            vk::StencilFaceFlags::FRONT_AND_BACK,
                            draw.stencil,
                        );
                    }
                    d.cmd_bind_vertex_buffers(cmd, 0, &[draw.mesh.vertices.raw], &[0]);
                    d.cmd_bind_vertex_buffers(
                        cmd,
                        1,
                        &[draw.texgen.0.raw, draw.texgen.1.raw],
                        &[0, 0],
                    );
                    d.cmd_bind_index_buffer(cmd, draw.indices.raw, 0, vk::IndexType::UINT32);
                    d.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, 0, 0);
                }
            }
            Ok(())
        })
    }
}

/// One reflector's shading: the pixels marked `stencil`, inside `area`,
/// drawn band by band where `bands` are given (scissors inside `area`).
pub struct CompositeDraw {
    pub stencil: u32,
    pub area: vk::Rect2D,
    pub bands: Vec<vk::Rect2D>,
    pub push: CompositePush,
    /// How many samples it blends: picks the pipeline variant.
    pub samples: usize,
    /// Binds the G-buffer, the map arrays of the reflector's EM resolution
    /// and the Fresnel LUT.
    pub set: vk::DescriptorSet,
}

/// Pass 2: every marked pixel shaded once from the G-buffer.
pub struct CompositePass<'a> {
    pub device: &'a Device,
    pub pipeline: &'a Pipeline,
    /// The frame's colour and depth/stencil (read only).
    pub target: Target<'a>,
    pub draws: Vec<CompositeDraw>,
    pub sampled: Vec<&'a Image>,
    pub name: &'static str,
}

impl Pass for CompositePass<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        let mut a = vec![
            Access::level(self.target.color, self.target.level, Usage::ColorTarget),
            Access::whole(self.target.depth, Usage::DepthRead),
        ];
        a.extend(
            self.sampled
                .iter()
                .map(|i| Access::whole(i, Usage::Sampled)),
        );
        a
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let union = self
            .draws
            .iter()
            .map(|d| Some(d.area))
            .reduce(union)
            .flatten();
        let attachments = Attachments {
            colors: &[self.target.color],
            load: ColorLoad::Keep,
            depth: self.target.depth,
            depth_usage: Usage::DepthRead,
            clear_depth: false,
            area: union,
        };
        attachments.render(self.device, cmd, || {
            let d = &self.device.device;
            for draw in &self.draws {
                let variant = COMPOSITE_SAMPLES
                    .iter()
                    .position(|&n| n as usize == draw.samples)
                    .ok_or_else(|| {
                        GpuError::Invalid(format!("composite of {} samples", draw.samples))
                    })?;
                self.pipeline
                    .bind_variant(cmd, variant, Some(draw.set), &draw.push)?;
                let scissors = match draw.bands.as_slice() {
                    [] => std::slice::from_ref(&draw.area),
                    bands => bands,
                };
                // SAFETY: the composite pipeline (no vertex input) is bound
                // inside dynamic rendering; every scissor lies in `area`,
                // hence in the render area (their union).
                unsafe {
                    d.cmd_set_stencil_reference(
                        cmd,
                        vk::StencilFaceFlags::FRONT_AND_BACK,
                        draw.stencil,
                    );
                    for scissor in scissors {
                        d.cmd_set_scissor(cmd, 0, std::slice::from_ref(scissor));
                        d.cmd_draw(cmd, 3, 1, 0, 0);
                    }
                }
            }
            Ok(())
        })
    }
}

/// What colour attachments start with.
#[derive(Clone, Copy)]
pub enum ColorLoad<'a> {
    /// What earlier passes left.
    Keep,
    /// Per attachment, cleared to a value, or undefined (None: every
    /// texel a later pass reads is written first).
    Clear(&'a [Option<[f32; 4]>]),
}

/// Colour attachments (level 0, layer 0) and a depth/stencil image, for
/// the multi-attachment passes.
pub struct Attachments<'a> {
    pub colors: &'a [&'a Image],
    pub load: ColorLoad<'a>,
    pub depth: &'a Image,
    /// `DepthTarget` (read and write) or `DepthRead` (tested only).
    pub depth_usage: Usage,
    /// Clear depth (to 1) and stencil (to 0) over the render area first,
    /// instead of loading what earlier passes left.
    pub clear_depth: bool,
    pub area: Option<vk::Rect2D>,
}

impl Attachments<'_> {
    /// Begins rendering, runs `draw`, ends.
    pub fn render(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        draw: impl FnOnce() -> GpuResult<()>,
    ) -> GpuResult<()> {
        let colors =
            self.colors
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let info = vk::RenderingAttachmentInfo::default()
                        .image_view(c.target_view(0, 0)?)
                        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                        .store_op(vk::AttachmentStoreOp::STORE);
                    Ok(match self.load {
                        ColorLoad::Keep => info.load_op(vk::AttachmentLoadOp::LOAD),
                        ColorLoad::Clear(values) => match values.get(i).copied().flatten() {
                            Some(value) => info.load_op(vk::AttachmentLoadOp::CLEAR).clear_value(
                                vk::ClearValue {
                                    color: vk::ClearColorValue { float32: value },
                                },
                            ),
                            None => info.load_op(vk::AttachmentLoadOp::DONT_CARE),
                        },
                    })
                })
                .collect::<GpuResult<Vec<_>>>()?;
        let (layout, store) = match self.depth_usage {
            Usage::DepthRead => (
                vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
                vk::AttachmentStoreOp::NONE,
            ),
            _ => (
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                vk::AttachmentStoreOp::STORE,
            ),
        };
        let depth_load = if self.clear_depth {
            vk::AttachmentLoadOp::CLEAR
        } else {
            vk::AttachmentLoadOp::LOAD
        };
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.target_view(0, 0)?)
            .image_layout(layout)
            .load_op(depth_load)
            .store_op(store)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            });
        let (width, height) = self.depth.desc.mip_extent(0);
        render_into(
            device,
            cmd,
            &colors,
            &depth,
            self.depth,
            vk::Extent2D { width, height },
            self.area,
            vk::FrontFace::COUNTER_CLOCKWISE,
            draw,
        )
    }
}

/// A `Vec4` of four `f32` values from up to four numbers (the rest 0).
pub fn vec4_of(values: &[f32]) -> Vec4 {
    let mut v = [0.0; 4];
    for (d, s) in v.iter_mut().zip(values) {
        *d = *s;
    }
    Vec4::from_array(v)
}
