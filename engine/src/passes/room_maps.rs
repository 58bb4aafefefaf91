//! The room's inferred light maps on the device: one RGBA16F image per
//! object with the solved MIP chain (every level as solved, not
//! re-filtered: the solve fitted all of them) and a vertex stream of the
//! object's light-map coordinates.

use crate::backend::upload::upload_image;
use crate::backend::{Buffer, Device, GpuResult, Image, ImageDesc};
use crate::compile::room::{ObjectRoomMap, RoomMaps};
use crate::graph::{Executor, Usage};
use ash::vk;
use half::f16;

/// One object's light map and light-map coordinates.
pub struct GpuRoomMap {
    pub object: usize,
    pub image: Image,
    pub uvs: Buffer,
}

/// Every light map of `maps`, uploaded.
pub fn upload_room_maps(
    device: &Device,
    executor: &mut Executor,
    maps: &RoomMaps,
) -> GpuResult<Vec<GpuRoomMap>> {
    maps.objects
        .iter()
        .map(|m| upload(device, executor, m))
        .collect()
}

fn upload(device: &Device, executor: &mut Executor, map: &ObjectRoomMap) -> GpuResult<GpuRoomMap> {
    let desc = ImageDesc {
        mip_levels: map.levels,
        ..ImageDesc::new_2d(vk::Format::R16G16B16A16_SFLOAT, map.width, map.height)
    }
    .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
    let image = Image::new(device, "room light map", desc)?;
    // Layout order (level-major, rows) is the upload order.
    let bytes: Vec<u8> = map
        .texels
        .iter()
        .flat_map(|t| t.map(f16::from_f32))
        .flat_map(f16::to_le_bytes)
        .collect();
    upload_image(device, executor.commands(), &image, &bytes)?;
    executor.states.assume(&image, Usage::Sampled);
    let uvs: Vec<[f32; 2]> = map.uvs.iter().map(|uv| uv.to_array()).collect();
    Ok(GpuRoomMap {
        object: map.object,
        image,
        uvs: Buffer::with_data(
            device,
            "room light-map uvs",
            vk::BufferUsageFlags::VERTEX_BUFFER,
            &uvs,
        )?,
    })
}
