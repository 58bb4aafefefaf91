//! Reading the device's images back to the CPU: the last frame, a
//! reflector's static EM, and the pixels the last deferred PEM frame covered.

use super::Renderer;
use crate::backend::{Buffer, GpuError, GpuResult};
use crate::passes::readback::ReadbackPass;
use ash::vk;
use glam::Vec3;
use half::f16;
use half::slice::HalfFloatSliceExt;

/// Every byte of `image` (all levels and layers), copied back through a
/// host-visible buffer by one read-back pass.
fn read_back(
    device: &crate::backend::Device,
    executor: &mut crate::graph::Executor,
    image: &crate::backend::Image,
    label: &str,
) -> GpuResult<Vec<u8>> {
    let bytes = crate::backend::upload::image_bytes(image)?;
    let buffer = Buffer::new(
        device,
        label,
        bytes,
        vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuToCpu,
    )?;
    let pass = ReadbackPass {
        device,
        image,
        buffer: &buffer,
    };
    executor.run(&[&pass])?;
    Ok(buffer.mapped()?[..bytes as usize].to_vec())
}

impl Renderer {
    /// The static EM of the `index`-th reflector (scene order): its cube
    /// size, its world-space EM origin and every texel of every MIP level as
    /// linear RGBA f32, level-major, then face, then rows.
    pub fn static_em(&mut self, index: usize) -> GpuResult<(u32, Vec3, Vec<[f32; 4]>)> {
        let Some(r) = self.reflectors.get(index) else {
            return Err(GpuError::Invalid(format!("no reflector {index}")));
        };
        let bytes = read_back(
            &self.device,
            &mut self.executor,
            &r.cube.color,
            "static EM read-back",
        )?;
        let texels = rgba16f_to_f32(&bytes);
        Ok((r.cube.color.desc.width, r.cube.origin, texels))
    }

    /// Reflector pixels the last deferred PEM frame covered (counted on the
    /// G-buffer read back: the cosine's clear value marks the rest).
    pub fn covered_pixels(&mut self) -> GpuResult<u64> {
        let bytes = read_back(
            &self.device,
            &mut self.executor,
            &self.gbuffer.images[2],
            "g-buffer read-back",
        )?;
        // A Vec<u8> need not be aligned for f32: collect, don't cast.
        let cos: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(cos.iter().filter(|&&c| c >= -1.5).count() as u64)
    }

    /// The last REM frame's blended sphere map (Σ weight × radiance, the
    /// weights' sum in alpha) as linear RGBA f32, rows from t = 0.
    pub fn rem_blended(&mut self) -> GpuResult<Vec<[f32; 4]>> {
        let Some(rem) = self.rem.as_ref() else {
            return Err(GpuError::Invalid("no set_rem()".into()));
        };
        let image = rem.gpu.blended();
        let bytes = read_back(&self.device, &mut self.executor, image, "rem read-back")?;
        Ok(rgba16f_to_f32(&bytes))
    }

    /// The last frame's pixels as linear RGBA f32, row-major from the top
    /// (alpha at most 1: the deferred composite marks its pixels above it).
    pub fn pixels(&self) -> GpuResult<Vec<[f32; 4]>> {
        Ok(half_pixels(self.frame_read_back()?))
    }

    /// The last frame as read back, RGBA16F (4 halves a pixel): a copy of
    /// half the bytes, for a caller that converts with [`half_pixels`] on
    /// another thread, off the next frame's way.
    pub fn frame_halves(&self) -> GpuResult<Vec<f16>> {
        Ok(self.frame_read_back()?.to_vec())
    }

    /// Which pixels of the last frame show a reflector, as its deferred
    /// composite marked them (an object in front of one hides it).
    pub fn reflector_pixels(&self) -> GpuResult<Vec<bool>> {
        // Unclamped: the composite's mark lies above an alpha of 1.
        Ok(
            rgba16f_to_f32(bytemuck::cast_slice(self.frame_read_back()?))
                .iter()
                .map(|p| p[3] > 0.5 * (1.0 + crate::shader_interface::REFLECTOR_ALPHA))
                .collect(),
        )
    }

    /// The last frame's RGBA16F texels in the read-back buffer.
    fn frame_read_back(&self) -> GpuResult<&[f16]> {
        let bytes = self.readback.mapped()?;
        let texels = (self.width * self.height) as usize;
        Ok(bytemuck::cast_slice(&bytes[..texels * 8]))
    }
}

/// A frame's RGBA16F read-back as [`Renderer::pixels`] gives it: linear
/// RGBA f32, alpha at most 1.
pub fn half_pixels(halves: &[f16]) -> Vec<[f32; 4]> {
    let mut pixels = rgba16f_to_f32(bytemuck::cast_slice(halves));
    for p in &mut pixels {
        p[3] = p[3].min(1.0);
    }
    pixels
}

/// RGBA16F texels read back from the device as linear RGBA f32 (`half`'s
/// slice conversion: F16C eight at a time where the CPU has it).
fn rgba16f_to_f32(bytes: &[u8]) -> Vec<[f32; 4]> {
    let halves = bytemuck::cast_slice::<u8, f16>(bytes);
    let mut texels = vec![[0.0f32; 4]; halves.len() / 4];
    halves[..texels.len() * 4].convert_to_f32_slice(bytemuck::cast_slice_mut(&mut texels));
    texels
}
