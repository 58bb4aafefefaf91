//! Copies every MIP level and layer of an image into a host-visible buffer,
//! level-major then layer then rows (the order of
//! `inference::solve::layout`); for a frame that is just its pixels. The
//! executor's end-of-frame barrier makes the copy visible to the host.

use crate::backend::upload::level_regions;
use crate::backend::{Buffer, Device, GpuError, GpuResult, Image};
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
        vec![Access::whole(self.image, Usage::TransferSrc)]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let (regions, bytes) = level_regions(&self.image.desc)?;
        if bytes > self.buffer.size {
            return Err(GpuError::Invalid(format!(
                "read-back of {bytes} bytes into a buffer of {}",
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
