//! A reflector's inside, where the eye looks between its parts (the gap
//! between a teapot's lid and body): the caps over its openings
//! (`inference::caps`), drawn with depth, both sides, so that it sees the
//! dark inside, as the tracer does, and not the room through the object,
//! as culled back faces showed (96 pixels of the teapot at 12° on the
//! orbit, 0–2 of 255 traced against ~155 drawn). The forward passes
//! (multipass, static EM, REM) draw them black; the deferred G-buffer
//! records "nothing drawn" and unmarks the stencil, so the room's cleared
//! black stays: where a reflector's part lies behind an opening (the body
//! seen into the spout's mouth), its mark would otherwise survive the cap
//! and the composite would shade the cap's "nothing drawn" there.
//! `shaders/reflector_interior.*`, `pem_gbuffer_interior.frag`.

use super::target::draw_mesh;
use crate::backend::{Device, GpuResult, Pipeline, PipelineDesc, StencilTest};
use crate::gpu_scene::GpuMesh;
use crate::shader_interface::{INTERIOR_ATTRIBUTES, PemPush, Vertex, spirv};
use ash::vk;
use glam::Mat4;

/// The inside's pipeline with `fragment_spirv` over `color_formats` (one
/// frame colour: `reflector_interior.frag`; the G-buffer's three:
/// `pem_gbuffer_interior.frag`, with `stencil` [`StencilTest::Unmark`]);
/// pushes a [`PemPush`] (its view_proj).
pub fn interior_pipeline(
    device: &Device,
    (name, fragment_spirv): (&str, &[u8]),
    color_formats: &[vk::Format],
    depth_format: vk::Format,
    stencil: StencilTest,
) -> GpuResult<Pipeline> {
    Pipeline::new(
        device,
        &PipelineDesc {
            name,
            vertex_spirv: spirv::REFLECTOR_INTERIOR_VERT,
            fragment_spirv,
            vertex_bindings: &[Vertex::BINDING],
            vertex_attributes: &INTERIOR_ATTRIBUTES,
            color_formats,
            depth_format,
            cull_mode: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_constant_size: size_of::<PemPush>() as u32,
            bindings: &[],
            blend: crate::backend::Blend::Replace,
            depth: crate::backend::DepthTest::TestWrite,
            stencil,
        },
    )
}

/// The black inside for a pass drawing into one frame colour.
pub fn black_interior(
    device: &Device,
    color: vk::Format,
    depth: vk::Format,
) -> GpuResult<Pipeline> {
    let names = ("reflector interior", spirv::REFLECTOR_INTERIOR_FRAG);
    interior_pipeline(device, names, &[color], depth, StencilTest::Off)
}

/// Records `caps` with `pipeline` (a [`black_interior`]) under
/// `view_proj`, inside a pass's rendering, after the reflectors' front
/// faces (which hide most of them from the depth test).
pub fn record_caps<'a>(
    device: &Device,
    cmd: vk::CommandBuffer,
    pipeline: &Pipeline,
    view_proj: Mat4,
    caps: impl IntoIterator<Item = &'a GpuMesh>,
) -> GpuResult<()> {
    let push = PemPush {
        view_proj,
        ..Default::default()
    };
    pipeline.bind(cmd, None, &push)?;
    for mesh in caps {
        draw_mesh(device, cmd, mesh, None);
    }
    Ok(())
}
