//! Copies a colour image (level 0, layer 0) into a host-visible buffer for
//! headless capture; the executor's end-of-frame barrier makes it visible.

use crate::backend::{Buffer, Device, GpuResult, Image};
use crate::graph::{Access, Pass, Usage};
use ash::vk;

pub struct ReadbackPass<'a> {
    pub device: &'a Device,
    pub image: &'a Image,
    pub buffer: &'a Buffer,
}

impl Pass for ReadbackPass<'_> {
    fn name(&self) -> &str {
        "readback"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![Access::level(self.image, 0, Usage::TransferSrc)]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let desc = self.image.desc;
        let region = vk::BufferImageCopy {
            buffer_offset: 0,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: desc.aspect(),
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            },
            image_offset: vk::Offset3D::default(),
            image_extent: vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            },
        };
        // SAFETY: the buffer was sized for width × height texels of this
        // format by the owner; the image is in TRANSFER_SRC (declared).
        unsafe {
            self.device.device.cmd_copy_image_to_buffer(
                cmd,
                self.image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.buffer.raw,
                &[region],
            )
        };
        Ok(())
    }
}

/// Copies every MIP level and layer of an image into a buffer, level-major
/// then layer then rows: the order of `inference::solve::layout`.
pub struct ImageReadbackPass<'a> {
    pub device: &'a Device,
    pub image: &'a Image,
    pub buffer: &'a Buffer,
}

impl Pass for ImageReadbackPass<'_> {
    fn name(&self) -> &str {
        "image_readback"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![Access::whole(self.image, Usage::TransferSrc)]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let (regions, offset) = crate::backend::upload::level_regions(&self.image.desc)?;
        if offset > self.buffer.size {
            return Err(crate::backend::GpuError::Invalid(format!(
                "read-back of {offset} bytes into a buffer of {}",
                self.buffer.size
            )));
        }
        // SAFETY: the regions fit the buffer (checked above); the image is in
        // TRANSFER_SRC for every level (declared access).
        unsafe {
            self.device.device.cmd_copy_image_to_buffer(
                cmd,
                self.image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.buffer.raw,
                &regions,
            )
        };
        Ok(())
    }
}
