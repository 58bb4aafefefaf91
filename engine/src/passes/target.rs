//! What the drawing passes share: dynamic rendering into one level and
//! layer of a colour + depth pair, and indexed mesh draws.

use crate::backend::{Buffer, Device, GpuResult, Image};
use crate::gpu_scene::GpuMesh;
use ash::vk;

/// A colour + depth pair to render into (one MIP level, one layer).
#[derive(Clone, Copy)]
pub struct Target<'a> {
    pub color: &'a Image,
    pub depth: &'a Image,
    pub level: u32,
    pub layer: u32,
    /// Clear both attachments first (else load what earlier passes drew).
    pub clear: bool,
    /// Winding of front faces as this target's projection sees them: cube
    /// faces are mirror images (see `cube.rs`), so they flip it.
    pub front_face: vk::FrontFace,
}

impl Target<'_> {
    pub fn extent(&self) -> vk::Extent2D {
        let (width, height) = self.color.desc.mip_extent(self.level);
        vk::Extent2D { width, height }
    }

    /// Begins rendering, runs `draw`, ends rendering.
    pub fn render(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        draw: impl FnOnce() -> GpuResult<()>,
    ) -> GpuResult<()> {
        let load = if self.clear {
            vk::AttachmentLoadOp::CLEAR
        } else {
            vk::AttachmentLoadOp::LOAD
        };
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(self.color.target_view(self.level, self.layer)?)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue { float32: [0.0; 4] },
            })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.target_view(self.level, self.layer)?)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            });
        let extent = self.extent();
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&color)
            .depth_attachment(&depth);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: the executor transitioned both attachments to the layouts
        // named here (the pass declares them as targets); views are alive.
        unsafe {
            device.device.cmd_begin_rendering(cmd, &info);
            device.device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.device.cmd_set_scissor(cmd, 0, &[area]);
            device.device.cmd_set_front_face(cmd, self.front_face);
        }
        let drawn = draw();
        // SAFETY: matches cmd_begin_rendering above.
        unsafe { device.device.cmd_end_rendering(cmd) };
        drawn
    }
}

/// Draws `mesh`, with `per_vertex` (if any) bound as vertex binding 1.
pub fn draw_mesh(
    device: &Device,
    cmd: vk::CommandBuffer,
    mesh: &GpuMesh,
    per_vertex: Option<&Buffer>,
) {
    // SAFETY: a compatible pipeline is bound inside dynamic rendering; the
    // buffers hold index_count valid indices and matching vertices.
    unsafe {
        let d = &device.device;
        d.cmd_bind_vertex_buffers(cmd, 0, &[mesh.vertices.raw], &[0]);
        if let Some(buffer) = per_vertex {
            d.cmd_bind_vertex_buffers(cmd, 1, &[buffer.raw], &[0]);
        }
        d.cmd_bind_index_buffer(cmd, mesh.indices.raw, 0, vk::IndexType::UINT32);
        d.cmd_draw_indexed(cmd, mesh.index_count, 1, 0, 0, 0);
    }
}
