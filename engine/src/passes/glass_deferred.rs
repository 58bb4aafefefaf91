//! Deferred glass (the default where per-sample shell maps blend): the
//! lens is rasterized once into a G-buffer of per-pixel lookups (both exit
//! rays with their levels of detail, both weights) while the stencil marks
//! its pixels; then one screen pass shades each marked pixel once, reading
//! both samples' maps. At τ = 10 the lens's small triangles make ~13
//! fragment invocations per covered pixel (2×2 quads), and the forward
//! pass paid its four cube lookups in each of them.

use super::pem_deferred::{Attachments, ColorLoad};
use super::target::Target;
use crate::backend::{
    Binding, Buffer, DepthTest, Device, Filtering, GpuResult, Image, ImageDesc, Pipeline,
    PipelineDesc, Sampler, StencilTest,
};
use crate::graph::{Access, Pass, Usage};
use crate::shader_interface::{GLASS_ATTRIBUTES, GLASS_BINDING, GlassPush, spirv};
use ash::vk;
use glam::{Mat4, Vec4};

/// G-buffer formats: the refracted and reflected paths' lookups with their
/// LODs (full floats: a lookup is a direction read at a fraction of a
/// texel), then their weights F·G (halves: colours in [0, 1]).
pub const GLASS_GBUFFER_FORMATS: [vk::Format; 4] = [
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
];

/// The stencil value marking the lens's pixels (the room pass before it
/// cleared the stencil to 0).
const LENS_MARK: u32 = 1;

/// The deferred glass pipelines, their G-buffer (at the frame's size) and
/// their sets over one cube-map array of per-sample shell maps.
pub struct DeferredGlass {
    device: Device,
    gbuffer_pipeline: Pipeline,
    composite: Pipeline,
    images: [Image; 4],
    gbuffer_set: vk::DescriptorSet,
    composite_set: vk::DescriptorSet,
    _texel: Sampler,
}

impl DeferredGlass {
    /// Pipelines and a `size` G-buffer reading `samples` through `sampler`
    /// (the forward pass's trilinear sampler: the same filtering).
    pub fn new(
        device: &Device,
        samples: &Image,
        sampler: &Sampler,
        (color, depth): (vk::Format, vk::Format),
        (width, height): (u32, u32),
    ) -> GpuResult<Self> {
        let cube = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let gbuffer_pipeline = Pipeline::new(
            device,
            &PipelineDesc {
                name: "glass g-buffer",
                vertex_spirv: spirv::GLASS_VERT,
                fragment_spirv: spirv::GLASS_GBUFFER_FRAG,
                vertex_bindings: &[GLASS_BINDING],
                vertex_attributes: &GLASS_ATTRIBUTES,
                color_formats: &GLASS_GBUFFER_FORMATS,
                depth_format: depth,
                cull_mode: vk::CullModeFlags::BACK,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                push_constant_size: size_of::<GlassPush>() as u32,
                bindings: &[cube],
                blend: crate::backend::Blend::Replace,
                depth: DepthTest::TestWrite,
                stencil: StencilTest::Mark,
            },
        )?;
        let composite = Pipeline::new(
            device,
            &PipelineDesc {
                name: "glass composite",
                vertex_spirv: spirv::PEM_COMPOSITE_VERT,
                fragment_spirv: spirv::GLASS_COMPOSITE_FRAG,
                vertex_bindings: &[],
                vertex_attributes: &[],
                color_formats: &[color],
                depth_format: depth,
                cull_mode: vk::CullModeFlags::NONE,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                push_constant_size: size_of::<GlassPush>() as u32,
                bindings: &[cube; 5],
                blend: crate::backend::Blend::Replace,
                depth: DepthTest::Off,
                stencil: StencilTest::Equal,
            },
        )?;
        let make = |i: usize, name: &str| {
            Image::new(
                device,
                name,
                ImageDesc::new_2d(GLASS_GBUFFER_FORMATS[i], width, height)
                    .usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED),
            )
        };
        let images = [
            make(0, "glass g-buffer refracted lookup")?,
            make(1, "glass g-buffer reflected lookup")?,
            make(2, "glass g-buffer refracted weight")?,
            make(3, "glass g-buffer reflected weight")?,
        ];
        let texel = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            Filtering::Nearest,
        )?;
        let map = Binding::Image(samples.view, sampler.raw);
        let gbuffer_set = gbuffer_pipeline.descriptor_set(&[map])?;
        let g = |i: usize| Binding::Image(images[i].view, texel.raw);
        let composite_set = composite.descriptor_set(&[g(0), g(1), g(2), g(3), map])?;
        Ok(Self {
            device: device.clone(),
            gbuffer_pipeline,
            composite,
            images,
            gbuffer_set,
            composite_set,
            _texel: texel,
        })
    }

    /// The G-buffer pass, then the composite into `target`'s colour inside
    /// `target.area`; `blend` is the two samples' layers and the second's
    /// weight. With `first` the G-buffer pass runs before the room: it
    /// clears depth and stencil over the whole frame and lays down the
    /// lens's depth, so the room's depth test skips what the lens covers
    /// (and the room unmarks what it draws in front of it); otherwise it
    /// tests against the room's depth.
    pub fn passes<'a>(
        &'a self,
        lens: DeferredLens<'a>,
        target: Target<'a>,
        (view_proj, blend): (Mat4, Vec4),
        samples: &'a Image,
        first: bool,
    ) -> [Box<dyn Pass + 'a>; 2] {
        // `Attachments` renders level 0, layer 0, counter-clockwise fronts:
        // the frame's own target, as glass frames give it.
        debug_assert!(
            target.level == 0
                && target.layer == 0
                && target.front_face == vk::FrontFace::COUNTER_CLOCKWISE
        );
        let push = GlassPush { view_proj, blend };
        [
            Box::new(LensGBufferPass {
                glass: self,
                lens,
                target,
                push,
                samples,
                first,
            }),
            Box::new(LensCompositePass {
                glass: self,
                bands: lens.bands,
                target,
                push,
                samples,
            }),
        ]
    }
}

/// The lens's uploaded stream (one-shell layout) and indices, and the
/// scissor bands covering its pixels (`passes::bands`; empty: the render
/// area).
#[derive(Clone, Copy)]
pub struct DeferredLens<'a> {
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    pub index_count: u32,
    pub bands: &'a [vk::Rect2D],
}

/// Pass 1: the lens into the G-buffer, its pixels marked in the stencil;
/// depth-tested against the room, or (`first`) laying the frame's depth
/// down before it.
struct LensGBufferPass<'a> {
    glass: &'a DeferredGlass,
    lens: DeferredLens<'a>,
    target: Target<'a>,
    push: GlassPush,
    samples: &'a Image,
    first: bool,
}

impl Pass for LensGBufferPass<'_> {
    fn name(&self) -> &str {
        "glass_gbuffer"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        let mut a: Vec<Access> = (self.glass.images.iter())
            .map(|i| Access::whole(i, Usage::ColorTarget))
            .collect();
        a.push(Access::whole(self.target.depth, Usage::DepthTarget));
        a.push(Access::whole(self.samples, Usage::Sampled));
        a
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let g = self.glass;
        let colors: Vec<&Image> = g.images.iter().collect();
        // Undefined where the lens is not: the composite reads marked
        // pixels only.
        let attachments = Attachments {
            colors: &colors,
            load: ColorLoad::Clear(&[None; 4]),
            depth: self.target.depth,
            depth_usage: Usage::DepthTarget,
            // First in the frame: depth and stencil cleared everywhere, as
            // the room pass after it keeps them.
            clear_depth: self.first,
            area: if self.first { None } else { self.target.area },
        };
        attachments.render(&g.device, cmd, || {
            if self.lens.index_count == 0 {
                return Ok(());
            }
            g.gbuffer_pipeline
                .bind(cmd, Some(g.gbuffer_set), &self.push)?;
            // SAFETY: the G-buffer pipeline (the one-shell glass stream) is
            // bound inside dynamic rendering; the index count is the
            // uploaded indices', which index the uploaded one-shell stream.
            unsafe {
                let d = &g.device.device;
                d.cmd_set_stencil_reference(cmd, vk::StencilFaceFlags::FRONT_AND_BACK, LENS_MARK);
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.lens.vertices.raw], &[0]);
                d.cmd_bind_index_buffer(cmd, self.lens.indices.raw, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cmd, self.lens.index_count, 1, 0, 0, 0);
            }
            Ok(())
        })
    }
}

/// Pass 2: every marked pixel shaded once from the G-buffer.
struct LensCompositePass<'a> {
    glass: &'a DeferredGlass,
    bands: &'a [vk::Rect2D],
    target: Target<'a>,
    push: GlassPush,
    samples: &'a Image,
}

impl Pass for LensCompositePass<'_> {
    fn name(&self) -> &str {
        "glass"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        let mut a = vec![
            Access::level(self.target.color, self.target.level, Usage::ColorTarget),
            Access::whole(self.target.depth, Usage::DepthRead),
            Access::whole(self.samples, Usage::Sampled),
        ];
        a.extend((self.glass.images.iter()).map(|i| Access::whole(i, Usage::Sampled)));
        a
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let g = self.glass;
        let attachments = Attachments {
            colors: &[self.target.color],
            load: ColorLoad::Keep,
            depth: self.target.depth,
            depth_usage: Usage::DepthRead,
            clear_depth: false,
            area: self.target.area,
        };
        // lavapipe runs the composite over every pixel a scissor lets
        // through, whatever the stencil rejects: bands, not the lens's
        // bounding rectangle (a third of which the lens covers).
        let area = self.target.area.unwrap_or(vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: self.target.extent(),
        });
        let scissors = match super::bands::clipped(self.bands, area) {
            bands if bands.is_empty() => vec![area],
            bands => bands,
        };
        attachments.render(&g.device, cmd, || {
            g.composite.bind(cmd, Some(g.composite_set), &self.push)?;
            // SAFETY: the composite pipeline (no vertex input) is bound
            // inside dynamic rendering; every scissor lies in the render
            // area (clipped to it).
            unsafe {
                let d = &g.device.device;
                d.cmd_set_stencil_reference(cmd, vk::StencilFaceFlags::FRONT_AND_BACK, LENS_MARK);
                for scissor in &scissors {
                    d.cmd_set_scissor(cmd, 0, std::slice::from_ref(scissor));
                    d.cmd_draw(cmd, 3, 1, 0, 0);
                }
            }
            Ok(())
        })
    }
}
