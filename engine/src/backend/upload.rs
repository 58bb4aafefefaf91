//! Set-up uploads: texel data for every level and layer of an image through
//! a staging buffer, leaving the image ready for sampling. (Per-frame data
//! goes through the frame's own passes instead.)

use super::buffer::Buffer;
use super::commands::Commands;
use super::device::Device;
use super::error::{GpuError, GpuResult};
use super::image::{Image, ImageDesc};
use ash::vk;
use gpu_allocator::MemoryLocation;

pub fn texel_size(format: vk::Format) -> Option<u64> {
    match format {
        vk::Format::R32_SFLOAT | vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB => Some(4),
        vk::Format::R16G16B16A16_SFLOAT => Some(8),
        vk::Format::R32G32B32A32_SFLOAT => Some(16),
        _ => None,
    }
}

/// One copy region per MIP level (all layers), tightly packed level-major
/// then layer then rows — the order uploads take and read-backs give —
/// and the total bytes.
pub fn level_regions(desc: &ImageDesc) -> GpuResult<(Vec<vk::BufferImageCopy>, u64)> {
    let texel = texel_size(desc.format)
        .ok_or_else(|| GpuError::Invalid(format!("no texel size for {:?}", desc.format)))?;
    let mut offset = 0u64;
    let regions = (0..desc.mip_levels)
        .map(|level| {
            let (w, h) = desc.mip_extent(level);
            let region = vk::BufferImageCopy {
                buffer_offset: offset,
                buffer_row_length: 0,
                buffer_image_height: 0,
                image_subresource: vk::ImageSubresourceLayers {
                    aspect_mask: desc.aspect(),
                    mip_level: level,
                    base_array_layer: 0,
                    layer_count: desc.layers(),
                },
                image_offset: vk::Offset3D::default(),
                image_extent: vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                },
            };
            offset += u64::from(w) * u64::from(h) * u64::from(desc.layers()) * texel;
            region
        })
        .collect();
    Ok((regions, offset))
}

/// The regions of one array element (all its levels and layers — one cube
/// or one 2D image), packed as [`level_regions`] packs a single image, and
/// its bytes: a decoded map in staging uploads into one slot of an array.
pub fn element_regions(
    desc: &ImageDesc,
    element: u32,
) -> GpuResult<(Vec<vk::BufferImageCopy>, u64)> {
    if element >= desc.array {
        return Err(GpuError::Invalid(format!(
            "array element {element} of {} elements",
            desc.array
        )));
    }
    let single = ImageDesc { array: 1, ..*desc };
    let (mut regions, bytes) = level_regions(&single)?;
    for r in &mut regions {
        r.image_subresource.base_array_layer = element * desc.element_layers();
    }
    Ok((regions, bytes))
}

/// Bytes of all levels × layers, level-major, tightly packed.
pub fn image_bytes(image: &Image) -> GpuResult<u64> {
    Ok(level_regions(&image.desc)?.1)
}

/// Uploads `data` (every level, each level's layers in order) and leaves the
/// whole image in SHADER_READ_ONLY_OPTIMAL.
pub fn upload_image(
    device: &Device,
    commands: &Commands,
    image: &Image,
    data: &[u8],
) -> GpuResult<()> {
    let expected = image_bytes(image)?;
    if data.len() as u64 != expected {
        return Err(GpuError::Invalid(format!(
            "upload of {} bytes into an image of {expected} bytes ({:?})",
            data.len(),
            image.desc
        )));
    }
    let mut staging = Buffer::new(
        device,
        "upload staging",
        expected,
        vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::CpuToGpu,
    )?;
    staging.mapped_mut()?[..data.len()].copy_from_slice(data);

    let desc = image.desc;
    let (regions, _) = level_regions(&desc)?;

    let cmd = commands.begin()?;
    let to_transfer = [vk::ImageMemoryBarrier2::default()
        .dst_stage_mask(vk::PipelineStageFlags2::COPY)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
        .image(image.raw)
        .subresource_range(desc.full_range())];
    let to_sampled = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::FRAGMENT_SHADER)
        .dst_access_mask(vk::AccessFlags2::SHADER_SAMPLED_READ)
        .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
        .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
        .image(image.raw)
        .subresource_range(desc.full_range())];
    // SAFETY: the staging buffer holds `expected` bytes matching `regions`;
    // the image is not used by any pending work (set-up time).
    unsafe {
        let d = &device.device;
        d.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().image_memory_barriers(&to_transfer),
        );
        d.cmd_copy_buffer_to_image(
            cmd,
            staging.raw,
            image.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &regions,
        );
        d.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().image_memory_barriers(&to_sampled),
        );
    }
    commands.submit_and_wait()
}
