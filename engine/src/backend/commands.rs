//! One command buffer with its fence: record, submit, wait. The engine runs
//! one frame in flight (it reads every frame back), so one suffices.

use super::device::Device;
use super::error::{GpuResult, VkContext};
use ash::vk;

pub struct Commands {
    device: Device,
    pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Commands {
    pub fn new(device: &Device) -> GpuResult<Self> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid device; pool destroyed in Drop.
        let pool = unsafe { device.device.create_command_pool(&pool_info, None) }
            .vk("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device.
        let cmd = unsafe { device.device.allocate_command_buffers(&alloc) }
            .vk("vkAllocateCommandBuffers")?[0];
        // SAFETY: valid device; fence destroyed in Drop.
        let fence = unsafe {
            device
                .device
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .vk("vkCreateFence")?;
        Ok(Self {
            device: device.clone(),
            pool,
            cmd,
            fence,
        })
    }

    pub fn begin(&self) -> GpuResult<vk::CommandBuffer> {
        let info = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the previous submission was waited for in `submit_and_wait`,
        // so the buffer is not pending.
        unsafe {
            self.device
                .device
                .reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            self.device
                .device
                .begin_command_buffer(self.cmd, &info)
                .vk("vkBeginCommandBuffer")?;
        }
        Ok(self.cmd)
    }

    /// Ends, submits and blocks until the GPU finished.
    pub fn submit_and_wait(&self) -> GpuResult<()> {
        let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos)];
        // SAFETY: the buffer is in the recording state (from `begin`); the
        // fence is unsignalled (reset after every wait); the queue is only
        // used from this thread, as vkDeviceWaitIdle's external
        // synchronization requires.
        unsafe {
            let d = &self.device.device;
            d.end_command_buffer(self.cmd).vk("vkEndCommandBuffer")?;
            d.queue_submit2(self.device.queue, &submit, self.fence)
                .vk("vkQueueSubmit2")?;
            if let Err(e) = d.wait_for_fences(&[self.fence], true, u64::MAX) {
                // The work may still run: let it finish before the caller
                // frees what it uses. (Best effort; the first error counts.)
                let _ = d.device_wait_idle();
                return Err(e).vk("vkWaitForFences");
            }
            d.reset_fences(&[self.fence]).vk("vkResetFences")?;
        }
        Ok(())
    }
}

impl Drop for Commands {
    fn drop(&mut self) {
        // SAFETY: every submission was waited for; nothing is pending.
        unsafe {
            self.device.device.destroy_fence(self.fence, None);
            self.device.device.destroy_command_pool(self.pool, None);
        }
    }
}
