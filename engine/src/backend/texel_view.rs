//! A buffer read through a typed view (`usamplerBuffer` + `texelFetch`).
//! On lavapipe a texel fetch is gathered by the texture unit's unrolled
//! code, where a storage-buffer load with a per-lane address runs a loop
//! over the lanes with a bounds check each: the same bytes read as texels
//! cost far less (README, relighting).

use super::buffer::Buffer;
use super::device::Device;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;

pub struct TexelView {
    device: Device,
    pub raw: vk::BufferView,
}

impl TexelView {
    /// A view of the whole of `buffer` (created with
    /// `UNIFORM_TEXEL_BUFFER` usage) as texels of `format`, `texel_bytes`
    /// each; fails with a message when the device's element limit is less.
    pub fn new(
        device: &Device,
        name: &str,
        buffer: &Buffer,
        format: vk::Format,
        texel_bytes: u64,
    ) -> GpuResult<Self> {
        let elements = buffer.size / texel_bytes;
        let limit = device.properties.limits.max_texel_buffer_elements as u64;
        if elements > limit {
            return Err(GpuError::Invalid(format!(
                "{name}: {elements} texels in a texel buffer, the device allows {limit}"
            )));
        }
        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw)
            .format(format)
            .offset(0)
            .range(elements * texel_bytes);
        // SAFETY: `buffer` is alive and was created on this device; the
        // range lies inside it and is a whole number of texels. The view is
        // destroyed in Drop; its owner keeps `buffer` alive at least as long.
        let raw =
            unsafe { device.device.create_buffer_view(&info, None) }.vk("vkCreateBufferView")?;
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl Drop for TexelView {
    fn drop(&mut self) {
        // SAFETY: owners drop GPU resources only after the fence of the last
        // frame that used them (the engine waits for every frame).
        unsafe { self.device.device.destroy_buffer_view(self.raw, None) };
    }
}
