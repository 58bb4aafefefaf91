//! Host-visible buffers (on lavapipe every memory type is host-visible, so
//! vertex data and read-back share one kind of allocation).

use super::device::Device;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

pub struct Buffer {
    device: Device,
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    pub fn new(
        device: &Device,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> GpuResult<Self> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        // SAFETY: valid device; the buffer is destroyed in Drop.
        let raw = unsafe { device.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { device.device.get_buffer_memory_requirements(raw) };
        let allocation = device
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| GpuError::Allocation {
                name: name.into(),
                source,
            });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unbound buffer, not used by any command.
                unsafe { device.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements and is
        // not bound to anything else.
        unsafe {
            device
                .device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        }
        .vk("vkBindBufferMemory")?;
        Ok(Self {
            device: device.clone(),
            raw,
            size,
            allocation: Some(allocation),
        })
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data<T: bytemuck::Pod>(
        device: &Device,
        name: &str,
        usage: vk::BufferUsageFlags,
        data: &[T],
    ) -> GpuResult<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer = Self::new(
            device,
            name,
            bytes.len() as u64,
            usage,
            MemoryLocation::CpuToGpu,
        )?;
        buffer.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        Ok(buffer)
    }

    pub fn mapped(&self) -> GpuResult<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(Allocation::mapped_slice)
            .ok_or_else(|| GpuError::Invalid("buffer is not host-visible".into()))
    }

    pub fn mapped_mut(&mut self) -> GpuResult<&mut [u8]> {
        self.allocation
            .as_mut()
            .and_then(Allocation::mapped_slice_mut)
            .ok_or_else(|| GpuError::Invalid("buffer is not host-visible".into()))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: owners drop GPU resources only after the fence of the last
        // frame that used them (the engine waits for every frame).
        unsafe { self.device.device.destroy_buffer(self.raw, None) };
        if let Some(allocation) = self.allocation.take() {
            let _ = self.device.allocator().free(allocation);
        }
    }
}
