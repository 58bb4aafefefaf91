//! Host-visible staging buffers that decoded maps are written into, then
//! copied to their slot images by the `upload` pass. A buffer is owned by
//! whoever fills it — the frame, or the decode-ahead worker, which writes
//! straight into it (no second copy) and hands it back — and returns to the
//! pool once its upload has run.

use crate::backend::{Buffer, Device, GpuResult};
use ash::vk;
use gpu_allocator::MemoryLocation;

pub struct StagingPool {
    device: Device,
    /// Bytes of every buffer: the largest map (RGBA f16, full MIP chain).
    bytes: u64,
    free: Vec<Buffer>,
    made: usize,
}

impl StagingPool {
    pub fn new(device: &Device, bytes: u64) -> Self {
        Self {
            device: device.clone(),
            bytes,
            free: Vec::new(),
            made: 0,
        }
    }

    /// A free buffer, made when none is left (the pool grows to what the
    /// busiest frame plus decoding ahead needs, then stays).
    pub fn take(&mut self) -> GpuResult<Buffer> {
        if let Some(b) = self.free.pop() {
            return Ok(b);
        }
        self.made += 1;
        Buffer::new(
            &self.device,
            &format!("map staging {}", self.made),
            self.bytes,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )
    }

    pub fn give(&mut self, buffer: Buffer) {
        self.free.push(buffer);
    }

    /// Buffers made so far (for the counters).
    pub fn made(&self) -> usize {
        self.made
    }
}
