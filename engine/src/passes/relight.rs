//! The relight pass: one full-screen triangle into a panorama-sized colour
//! target, `Σ C_i Y_i(L)` per pixel from the signed SH maps
//! (`shaders/relight_directional.frag`, `relight_point.frag`). No depth: every pixel is written once.

use crate::backend::{Device, GpuResult, Image, Pipeline};
use crate::graph::{Access, Pass, Usage};
use crate::shader_interface::RelightPush;
use ash::vk;

pub struct RelightPass<'a> {
    pub device: &'a Device,
    pub pipeline: &'a Pipeline,
    /// Binds the SH maps' texel buffer (binding 0, written once by the
    /// host before any frame) and `positions` (binding 1).
    pub set: vk::DescriptorSet,
    pub positions: &'a Image,
    pub target: &'a Image,
    pub push: RelightPush,
}

impl Pass for RelightPass<'_> {
    fn name(&self) -> &str {
        "relight"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![
            Access::level(self.target, 0, Usage::ColorTarget),
            Access::whole(self.positions, Usage::Sampled),
        ]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let view = self.target.target_view(0, 0)?;
        let extent = self.target.desc.mip_extent(0);
        let draw = (self.pipeline, self.set);
        draw_fullscreen(self.device, cmd, view, extent, draw, &self.push)
    }
}

/// One full-screen triangle into `view` (`width × height`, colour only)
/// with `pipeline` (no vertex input), its set and push constants.
pub fn draw_fullscreen<P: bytemuck::Pod>(
    device: &Device,
    cmd: vk::CommandBuffer,
    view: vk::ImageView,
    (width, height): (u32, u32),
    (pipeline, set): (&Pipeline, vk::DescriptorSet),
    push: &P,
) -> GpuResult<()> {
    let area = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent: vk::Extent2D { width, height },
    };
    let color = [vk::RenderingAttachmentInfo::default()
        .image_view(view)
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::DONT_CARE)
        .store_op(vk::AttachmentStoreOp::STORE)];
    let info = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(&color);
    let viewport = vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: width as f32,
        height: height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let d = &device.device;
    // SAFETY: the caller's pass declared `view`'s image as a colour target,
    // so the executor put it in COLOR_ATTACHMENT_OPTIMAL, and its sampled
    // images in SHADER_READ_ONLY_OPTIMAL; the pipeline's formats match
    // (colour only, no depth).
    unsafe {
        d.cmd_begin_rendering(cmd, &info);
        d.cmd_set_viewport(cmd, 0, &[viewport]);
        d.cmd_set_scissor(cmd, 0, &[area]);
        d.cmd_set_front_face(cmd, vk::FrontFace::COUNTER_CLOCKWISE);
    }
    let bound = pipeline.bind(cmd, Some(set), push);
    // SAFETY: inside the rendering begun above; the bound pipeline has no
    // vertex input (the triangle comes from gl_VertexIndex).
    unsafe {
        if bound.is_ok() {
            d.cmd_draw(cmd, 3, 1, 0, 0);
        }
        d.cmd_end_rendering(cmd);
    }
    bound
}
