//! The fixed-function state of a graphics pipeline from its
//! [`PipelineDesc`]: blending, depth and stencil, what is dynamic.

use super::error::{GpuResult, VkContext};
use super::pipeline::{Blend, DepthTest, PipelineDesc, StencilTest};
use ash::vk;

/// # Safety
/// `layout` and both modules must belong to `d`.
pub(super) unsafe fn create_graphics_pipeline(
    d: &ash::Device,
    desc: &PipelineDesc,
    layout: vk::PipelineLayout,
    (vertex, fragment): (vk::ShaderModule, vk::ShaderModule),
    spec: Option<u32>,
) -> GpuResult<vk::Pipeline> {
    // The fragment shader's constant 0, when a variant sets it.
    let entries = [vk::SpecializationMapEntry {
        constant_id: 0,
        offset: 0,
        size: size_of::<u32>(),
    }];
    let data = spec.unwrap_or(0).to_ne_bytes();
    let specialization = vk::SpecializationInfo::default()
        .map_entries(&entries)
        .data(&data);
    let mut fragment_stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::FRAGMENT)
        .module(fragment)
        .name(c"main");
    if spec.is_some() {
        fragment_stage = fragment_stage.specialization_info(&specialization);
    }
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vertex)
            .name(c"main"),
        fragment_stage,
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(desc.vertex_bindings)
        .vertex_attribute_descriptions(desc.vertex_attributes);
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(desc.cull_mode)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = depth_stencil_state(desc);
    let blend_attachments = color_blend_attachments(desc);
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = dynamic_states(desc);
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(desc.color_formats)
        .depth_attachment_format(desc.depth_format)
        .stencil_attachment_format(stencil_format(desc.depth_format));
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering);
    // SAFETY: every pointer in `info` borrows locals alive for the call.
    unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
        .map(|p| p[0])
        .map_err(|(_, e)| e)
        .vk("vkCreateGraphicsPipelines")
}

/// One blend state per colour attachment: the first blended by alpha when
/// `desc` asks for it, every other written as is.
fn color_blend_attachments(desc: &PipelineDesc) -> Vec<vk::PipelineColorBlendAttachmentState> {
    use vk::BlendFactor as F;
    let plain = vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::RGBA);
    // Source and destination factors of colour, then of alpha; both added.
    let blended = |[color_src, color_dst, alpha_src, alpha_dst]: [F; 4]| {
        plain
            .blend_enable(true)
            .src_color_blend_factor(color_src)
            .dst_color_blend_factor(color_dst)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(alpha_src)
            .dst_alpha_blend_factor(alpha_dst)
            .alpha_blend_op(vk::BlendOp::ADD)
    };
    let attachment = match desc.blend {
        Blend::Replace => plain,
        Blend::ByAlpha => blended([F::SRC_ALPHA, F::ONE_MINUS_SRC_ALPHA, F::ZERO, F::ONE]),
        Blend::Add => blended([F::ONE; 4]),
    };
    (0..desc.color_formats.len())
        .map(|i| if i == 0 { attachment } else { plain })
        .collect()
}

/// The state set per draw rather than baked in. Front face is dynamic: the
/// same pipeline renders mirrored cube faces; so is the stencil reference:
/// one pipeline marks or tests every value.
fn dynamic_states(desc: &PipelineDesc) -> Vec<vk::DynamicState> {
    let mut dynamic_states = vec![
        vk::DynamicState::VIEWPORT,
        vk::DynamicState::SCISSOR,
        vk::DynamicState::FRONT_FACE,
    ];
    if matches!(desc.stencil, StencilTest::Mark | StencilTest::Equal) {
        dynamic_states.push(vk::DynamicState::STENCIL_REFERENCE);
    }
    dynamic_states
}

/// The stencil attachment format: the depth format when it has a stencil
/// aspect, else none.
fn stencil_format(depth_format: vk::Format) -> vk::Format {
    if matches!(
        depth_format,
        vk::Format::D32_SFLOAT_S8_UINT | vk::Format::D24_UNORM_S8_UINT
    ) {
        depth_format
    } else {
        vk::Format::UNDEFINED
    }
}

/// Depth and stencil state from `desc`.
fn depth_stencil_state(desc: &PipelineDesc) -> vk::PipelineDepthStencilStateCreateInfo<'static> {
    let depth = desc.depth == DepthTest::TestWrite;
    let op = |compare, pass, reference| vk::StencilOpState {
        fail_op: vk::StencilOp::KEEP,
        pass_op: pass,
        depth_fail_op: vk::StencilOp::KEEP,
        compare_op: compare,
        compare_mask: 0xff,
        write_mask: 0xff,
        reference,
    };
    let (stencil, face) = match desc.stencil {
        StencilTest::Off => (false, op(vk::CompareOp::ALWAYS, vk::StencilOp::KEEP, 0)),
        StencilTest::Mark => (true, op(vk::CompareOp::ALWAYS, vk::StencilOp::REPLACE, 0)),
        StencilTest::Unmark => (true, op(vk::CompareOp::ALWAYS, vk::StencilOp::ZERO, 0)),
        StencilTest::Equal => (true, op(vk::CompareOp::EQUAL, vk::StencilOp::KEEP, 0)),
    };
    vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(depth)
        .depth_write_enable(depth)
        .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL)
        .stencil_test_enable(stencil)
        .front(face)
        .back(face)
}
