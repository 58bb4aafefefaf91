//! The scene's meshes and textures on the device: one vertex and index
//! buffer per object, one RGBA16F image with a CPU box-filtered MIP chain
//! per baked texture, the trilinear sampler the room uses and the
//! nearest-MIP-level one its light maps use.

use crate::backend::upload::upload_image;
use crate::backend::{Buffer, Device, Filtering, GpuResult, Image, ImageDesc, Sampler};
use crate::graph::{Executor, Usage};
use crate::shader_interface::Vertex;
use ash::vk;
use half::f16;
use inference::scene::{Mesh, Scene, Texture};

pub struct GpuMesh {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
}

impl GpuMesh {
    pub fn upload(device: &Device, name: &str, mesh: &Mesh) -> GpuResult<Self> {
        let vertices: Vec<Vertex> = (0..mesh.positions.len())
            .map(|i| Vertex {
                position: mesh.positions[i].to_array(),
                normal: mesh.normals.get(i).copied().unwrap_or_default().to_array(),
                uv: mesh.uvs.get(i).copied().unwrap_or_default().to_array(),
            })
            .collect();
        Ok(Self {
            vertices: Buffer::with_data(
                device,
                name,
                vk::BufferUsageFlags::VERTEX_BUFFER,
                &vertices,
            )?,
            indices: Buffer::with_data(
                device,
                name,
                vk::BufferUsageFlags::INDEX_BUFFER,
                &mesh.indices,
            )?,
            index_count: mesh.indices.len() as u32,
        })
    }
}

pub struct GpuScene {
    /// Parallel to `scene.objects`.
    pub meshes: Vec<GpuMesh>,
    /// Parallel to `scene.objects`: a mirror or glossy object's caps over
    /// its openings (`inference::caps`, drawn black as its inside), None
    /// for other objects and closed meshes.
    pub caps: Vec<Option<GpuMesh>>,
    /// Parallel to `scene.textures`.
    pub textures: Vec<Image>,
    /// 1×1 white, bound where a material has no texture.
    pub white: Image,
    pub sampler: Sampler,
    /// Light maps: repeat, the nearest MIP level only — one bilinear fetch
    /// instead of trilinear's two, what keeps the inferred room as cheap as
    /// the analytic one (the light maps are solved for it).
    pub light_sampler: Sampler,
}

impl GpuScene {
    pub fn upload(device: &Device, executor: &mut Executor, scene: &Scene) -> GpuResult<Self> {
        let meshes = scene
            .objects
            .iter()
            .map(|o| GpuMesh::upload(device, &o.name, &o.mesh))
            .collect::<GpuResult<Vec<_>>>()?;
        let caps = scene
            .objects
            .iter()
            .map(|o| upload_caps(device, scene, o))
            .collect::<GpuResult<Vec<_>>>()?;
        let mut textures = Vec::with_capacity(scene.textures.len());
        for texture in &scene.textures {
            textures.push(upload_texture(device, executor, texture)?);
        }
        let white = upload_texture(
            device,
            executor,
            &Texture {
                name: "white".into(),
                width: 1,
                height: 1,
                texels: vec![[1.0; 4]],
                pattern: None,
            },
        )?;
        Ok(Self {
            meshes,
            caps,
            textures,
            white,
            sampler: Sampler::trilinear(device, vk::SamplerAddressMode::REPEAT)?,
            light_sampler: Sampler::new(
                device,
                vk::SamplerAddressMode::REPEAT,
                Filtering::MipNearest,
            )?,
        })
    }

    /// The image a material's optional texture index names (white if none).
    pub fn texture(&self, index: Option<usize>) -> &Image {
        index
            .and_then(|i| self.textures.get(i))
            .unwrap_or(&self.white)
    }
}

/// The caps of `o` when it reflects and has openings.
fn upload_caps(
    device: &Device,
    scene: &Scene,
    o: &inference::scene::Object,
) -> GpuResult<Option<GpuMesh>> {
    use inference::scene::Material;
    let reflects = matches!(
        scene.materials.get(o.material),
        Some(Material::Mirror { .. } | Material::Glossy { .. })
    );
    let caps = match reflects {
        true => inference::caps::boundary_caps(&o.mesh),
        false => return Ok(None),
    };
    if caps.indices.is_empty() {
        return Ok(None);
    }
    GpuMesh::upload(device, &format!("{} caps", o.name), &caps).map(Some)
}

fn upload_texture(device: &Device, executor: &mut Executor, texture: &Texture) -> GpuResult<Image> {
    let desc = ImageDesc::new_2d(
        vk::Format::R16G16B16A16_SFLOAT,
        texture.width,
        texture.height,
    )
    .all_mip_levels()
    .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
    let image = Image::new(device, &texture.name, desc)?;
    let levels = mip_chain(texture.width, texture.height, &texture.texels);
    let bytes: Vec<u8> = levels
        .iter()
        .flatten()
        .flat_map(|t| t.map(f16::from_f32))
        .flat_map(f16::to_le_bytes)
        .collect();
    upload_image(device, executor.commands(), &image, &bytes)?;
    executor.states.assume(&image, Usage::Sampled);
    Ok(image)
}

/// Every MIP level, each the 2×2 box average of the previous one (edge
/// texels repeat where a size is odd), down to 1×1.
pub fn mip_chain(width: u32, height: u32, base: &[[f32; 4]]) -> Vec<Vec<[f32; 4]>> {
    let mut levels = vec![base.to_vec()];
    let (mut w, mut h) = (width.max(1) as usize, height.max(1) as usize);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let prev = &levels[levels.len() - 1];
        let at = |x: usize, y: usize| prev[y.min(h - 1) * w + x.min(w - 1)];
        let mut next = Vec::with_capacity(nw * nh);
        for y in 0..nh {
            for x in 0..nw {
                let texels = [
                    at(2 * x, 2 * y),
                    at(2 * x + 1, 2 * y),
                    at(2 * x, 2 * y + 1),
                    at(2 * x + 1, 2 * y + 1),
                ];
                next.push(std::array::from_fn(|c| {
                    texels.iter().map(|t| t[c]).sum::<f32>() * 0.25
                }));
            }
        }
        levels.push(next);
        (w, h) = (nw, nh);
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_chain_reaches_one_texel_and_preserves_mean() {
        let texels: Vec<[f32; 4]> = (0..64).map(|i| [i as f32, 0.0, 1.0, 1.0]).collect();
        let levels = mip_chain(8, 8, &texels);
        assert_eq!(
            levels.iter().map(Vec::len).collect::<Vec<_>>(),
            [64, 16, 4, 1]
        );
        assert!((levels[3][0][0] - 31.5).abs() < 1e-4);
    }

    #[test]
    fn mip_chain_of_non_square_texture() {
        let levels = mip_chain(4, 1, &[[1.0; 4], [3.0; 4], [5.0; 4], [7.0; 4]]);
        assert_eq!(levels.len(), 3);
        assert_eq!(levels[2][0][0], 4.0);
    }
}
