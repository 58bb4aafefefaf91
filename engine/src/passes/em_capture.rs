//! The static environment map: the room rendered into the six faces of a
//! cube at the reflector's EM origin, then every MIP level down-sampled.

use super::room::RoomRenderer;
use super::target::{Load, Target};
use crate::backend::{Device, GpuResult, Image, ImageDesc};
use crate::cube::{FACE_COUNT, face_view_proj};
use crate::gpu_scene::GpuScene;
use crate::graph::{Access, Pass, Usage};
use ash::vk;
use glam::Vec3;

/// A cube colour map with all MIP levels and the depth cube it renders with.
pub struct CubeTarget {
    pub color: Image,
    pub depth: Image,
    pub origin: Vec3,
}

impl CubeTarget {
    pub fn new(
        device: &Device,
        name: &str,
        size: u32,
        format: vk::Format,
        origin: Vec3,
    ) -> GpuResult<Self> {
        let color = Image::new(
            device,
            name,
            ImageDesc::new_cube(format, size).all_mip_levels().usage(
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST,
            ),
        )?;
        let depth = Image::new(
            device,
            name,
            ImageDesc::new_cube(crate::renderer::DEPTH_FORMAT, size)
                .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        Ok(Self {
            color,
            depth,
            origin,
        })
    }
}

/// Renders the room into level 0 of every face.
pub struct EmCapturePass<'a> {
    pub room: &'a RoomRenderer,
    pub gpu: &'a GpuScene,
    pub cube: &'a CubeTarget,
    pub near: f32,
    pub far: f32,
}

impl Pass for EmCapturePass<'_> {
    fn name(&self) -> &str {
        "em_capture"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![
            Access::level(&self.cube.color, 0, Usage::ColorTarget),
            Access::level(&self.cube.depth, 0, Usage::DepthTarget),
        ]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        for face in 0..FACE_COUNT {
            let target = Target {
                color: &self.cube.color,
                depth: &self.cube.depth,
                level: 0,
                layer: face,
                load: Load::Clear,
                front_face: vk::FrontFace::CLOCKWISE,
                area: None,
            };
            let view_proj = face_view_proj(face, self.cube.origin, self.near, self.far);
            target.render(self.room_device(), cmd, || {
                self.room.draw(cmd, self.gpu, view_proj)
            })?;
        }
        Ok(())
    }
}

impl EmCapturePass<'_> {
    fn room_device(&self) -> &Device {
        self.room.device()
    }
}

/// Down-samples MIP level `level − 1` into `level` (all layers), linear.
pub struct MipPass<'a> {
    pub device: &'a Device,
    pub image: &'a Image,
    pub level: u32,
    pub name: String,
}

impl Pass for MipPass<'_> {
    fn name(&self) -> &str {
        &self.name
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![
            Access::level(self.image, self.level - 1, Usage::TransferSrc),
            Access::level(self.image, self.level, Usage::TransferDst),
        ]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let desc = self.image.desc;
        let corner = |level: u32| {
            let (w, h) = desc.mip_extent(level);
            [
                vk::Offset3D::default(),
                vk::Offset3D {
                    x: w as i32,
                    y: h as i32,
                    z: 1,
                },
            ]
        };
        let layers = |level: u32| vk::ImageSubresourceLayers {
            aspect_mask: desc.aspect(),
            mip_level: level,
            base_array_layer: 0,
            layer_count: desc.layers(),
        };
        let region = vk::ImageBlit {
            src_subresource: layers(self.level - 1),
            src_offsets: corner(self.level - 1),
            dst_subresource: layers(self.level),
            dst_offsets: corner(self.level),
        };
        // SAFETY: the executor put level−1 in TRANSFER_SRC and level in
        // TRANSFER_DST (declared accesses); RGBA16F supports linear blits.
        unsafe {
            self.device.device.cmd_blit_image(
                cmd,
                self.image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                vk::Filter::LINEAR,
            )
        };
        Ok(())
    }
}
