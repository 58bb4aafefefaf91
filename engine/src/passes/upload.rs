//! Copies from staging buffers into sampled images: how decoded maps reach
//! the device during playback (one pass, so the counters show its cost).

use crate::backend::upload::{element_regions, level_regions};
use crate::backend::{Buffer, Device, GpuResult, Image};
use crate::graph::{Access, Pass, Usage};
use ash::vk;

/// One image filled from `buffer` at byte `offset`: every MIP level and
/// layer, tightly packed level-major (see `level_regions`).
pub struct Upload<'a> {
    pub buffer: &'a Buffer,
    pub offset: u64,
    pub image: &'a Image,
    /// One element of an array image (None: the whole image).
    pub element: Option<u32>,
}

pub struct UploadPass<'a> {
    pub device: &'a Device,
    pub uploads: Vec<Upload<'a>>,
}

impl Pass for UploadPass<'_> {
    fn name(&self) -> &str {
        "upload"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.uploads
            .iter()
            .map(|u| Access::whole(u.image, Usage::TransferDst))
            .collect()
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        for upload in &self.uploads {
            let (mut regions, bytes) = match upload.element {
                Some(e) => element_regions(&upload.image.desc, e)?,
                None => level_regions(&upload.image.desc)?,
            };
            if upload.offset + bytes > upload.buffer.size {
                return Err(crate::backend::GpuError::Invalid(format!(
                    "upload of {bytes} bytes at {} overruns a {}-byte staging buffer",
                    upload.offset, upload.buffer.size
                )));
            }
            for r in &mut regions {
                r.buffer_offset += upload.offset;
            }
            // SAFETY: the executor moved the image to TRANSFER_DST_OPTIMAL
            // (declared above); the regions lie inside both resources (checked
            // above for the buffer, by construction for the image).
            unsafe {
                self.device.device.cmd_copy_buffer_to_image(
                    cmd,
                    upload.buffer.raw,
                    upload.image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &regions,
                )
            };
        }
        Ok(())
    }
}
