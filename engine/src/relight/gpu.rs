//! The relightable panorama on the device: `k` signed SH maps as one texel
//! buffer of RGBA16F pairs, texel-major (a pixel's k coefficients side by
//! side, read as RGBA32UI texels: measured faster on lavapipe than k layers
//! of a 2D-array image or the same bytes as a storage buffer, see the
//! README), the position panorama for point lights, the relit target, and
//! the pass that fills it for one light per frame.

use crate::backend::upload::upload_image;
use crate::backend::{
    Buffer, DepthTest, Device, GpuError, GpuResult, Image, ImageDesc, Pipeline, PipelineDesc,
    Sampler, StencilTest, TexelView,
};
use crate::graph::{Executor, Usage};
use crate::passes::readback::ReadbackPass;
use crate::passes::relight::RelightPass;
use crate::shader_interface::{RelightPush, spirv};
use ash::vk;
use glam::{Vec3, Vec4};
use half::f16;
use inference::relight::sh::{self, MAX_K};
use inference::relight::{Panorama, ShMaps};

/// The light of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GpuLight {
    Directional { to_light: Vec3, irradiance: Vec3 },
    Point { position: Vec3, intensity: Vec3 },
}

pub struct RelightGpu {
    device: Device,
    /// Directional and point-light pipelines and their descriptor sets.
    pipelines: [(Pipeline, vk::DescriptorSet); 2],
    _sampler: Sampler,
    // Declared before `maps`: the view is destroyed before its buffer.
    _map_view: TexelView,
    maps: Buffer,
    positions: Image,
    pub target: Image,
    readback: Buffer,
    pub k: usize,
    pub panorama: Panorama,
}

const TARGET_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

impl RelightGpu {
    /// Uploads the first `k` maps of `maps` and the per-texel `positions`.
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        maps: &ShMaps,
        k: usize,
        positions: &[Vec3],
    ) -> GpuResult<Self> {
        let p = maps.panorama;
        if sh::bands(k).is_none() || k > maps.k || positions.len() != p.texels() {
            return Err(GpuError::Invalid(format!(
                "relight: k = {k} (expected a square ≤ {} and ≤ the {} maps given), {} positions \
                 for {} texels",
                MAX_K,
                maps.k,
                positions.len(),
                p.texels()
            )));
        }
        let map_buffer = upload_maps(device, maps, k)?;
        let map_view = TexelView::new(
            device,
            "relight sh maps",
            &map_buffer,
            vk::Format::R32G32B32A32_UINT,
            16,
        )?;
        let position_image = upload_positions(device, executor, p, positions)?;
        let target = Image::new(
            device,
            "relit panorama",
            ImageDesc::new_2d(TARGET_FORMAT, p.width, p.height).usage(
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::SAMPLED,
            ),
        )?;
        let sampler = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            crate::backend::Filtering::Nearest,
        )?;
        let bindings = [
            crate::backend::Binding::Texels(&map_view),
            crate::backend::Binding::Image(position_image.view, sampler.raw),
        ];
        let with_set = |fragment, name| -> GpuResult<(Pipeline, vk::DescriptorSet)> {
            let pipeline = relight_pipeline(device, fragment, name)?;
            let set = pipeline.descriptor_set(&bindings)?;
            Ok((pipeline, set))
        };
        let pipelines = [
            with_set(spirv::RELIGHT_DIRECTIONAL_FRAG, "relight directional")?,
            with_set(spirv::RELIGHT_POINT_FRAG, "relight point")?,
        ];
        let readback = Buffer::new(
            device,
            "relit read-back",
            p.texels() as u64 * 16,
            vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuToCpu,
        )?;
        Ok(Self {
            device: device.clone(),
            pipelines,
            _sampler: sampler,
            _map_view: map_view,
            maps: map_buffer,
            positions: position_image,
            target,
            readback,
            k,
            panorama: p,
        })
    }

    /// The push constants for `light`: scalar weights `Y_i(L₀)` for a
    /// directional light, the position for a point light.
    pub fn push(&self, light: GpuLight) -> RelightPush {
        let mut push = RelightPush::default();
        let k = self.k as f32;
        match light {
            GpuLight::Directional {
                to_light,
                irradiance,
            } => {
                let mut y = [0.0f32; MAX_K];
                sh::eval(to_light, &mut y[..self.k]);
                for (w, c) in push.weights.iter_mut().zip(y.chunks_exact(4)) {
                    *w = Vec4::from_slice(c);
                }
                push.light = Vec4::new(0.0, 0.0, 0.0, y[24]);
                push.power = irradiance.extend(k);
            }
            GpuLight::Point {
                position,
                intensity,
            } => {
                push.light = position.extend(0.0);
                push.power = intensity.extend(k);
            }
        }
        push
    }

    /// Bytes of the SH maps on the device.
    pub fn map_bytes(&self) -> u64 {
        self.maps.size
    }

    /// The frame's pass for `light`.
    pub fn pass(&self, light: GpuLight) -> RelightPass<'_> {
        let (pipeline, set) = match light {
            GpuLight::Directional { .. } => &self.pipelines[0],
            GpuLight::Point { .. } => &self.pipelines[1],
        };
        RelightPass {
            device: &self.device,
            pipeline,
            set: *set,
            positions: &self.positions,
            target: &self.target,
            push: self.push(light),
        }
    }

    /// Relights once; the pass's GPU time in milliseconds.
    pub fn render(&self, executor: &mut Executor, light: GpuLight) -> GpuResult<f64> {
        let timings = executor.run(&[&self.pass(light)])?;
        Ok(timings.first().map_or(0.0, |t| t.sample.gpu_ms))
    }

    /// Relights once and reads the panorama back (row-major RGB).
    pub fn render_and_read(
        &self,
        executor: &mut Executor,
        light: GpuLight,
    ) -> GpuResult<Vec<Vec3>> {
        let readback = ReadbackPass {
            device: &self.device,
            image: &self.target,
            buffer: &self.readback,
        };
        executor.run(&[&self.pass(light), &readback])?;
        let bytes = self.readback.mapped()?;
        Ok(bytes[..self.panorama.texels() * 16]
            .chunks_exact(16)
            .map(|t| {
                let f = |i: usize| f32::from_le_bytes([t[i], t[i + 1], t[i + 2], t[i + 3]]);
                Vec3::new(f(0), f(4), f(8))
            })
            .collect())
    }
}

/// The first `k` maps, texel-major RGBA16F (the shader's `pairs`): texel t,
/// coefficient i at t·s + i, s = k rounded up to even (the padding stays zero).
fn upload_maps(device: &Device, maps: &ShMaps, k: usize) -> GpuResult<Buffer> {
    let stride = k.div_ceil(2) * 2;
    let mut halves = vec![f16::ZERO; maps.panorama.texels() * stride * 4];
    for i in 0..k {
        for (t, c) in maps.plane(i).chunks_exact(3).enumerate() {
            let at = (t * stride + i) * 4;
            for (j, x) in c.iter().enumerate() {
                halves[at + j] = f16::from_f32(*x);
            }
        }
    }
    Buffer::with_data(
        device,
        "relight sh maps",
        vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
        &halves.iter().map(|h| h.to_bits()).collect::<Vec<u16>>(),
    )
}

/// The position panorama as an RGBA32F image (xyz, w = 1).
fn upload_positions(
    device: &Device,
    executor: &mut Executor,
    p: Panorama,
    positions: &[Vec3],
) -> GpuResult<Image> {
    let image = Image::new(
        device,
        "relight positions",
        ImageDesc::new_2d(vk::Format::R32G32B32A32_SFLOAT, p.width, p.height)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    let bytes: Vec<u8> = positions
        .iter()
        .flat_map(|v| [v.x, v.y, v.z, 1.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    upload_image(device, executor.commands(), &image, &bytes)?;
    executor.states.assume(&image, Usage::Sampled);
    Ok(image)
}

fn relight_pipeline(device: &Device, fragment: &[u8], name: &str) -> GpuResult<Pipeline> {
    Pipeline::new(
        device,
        &PipelineDesc {
            name,
            vertex_spirv: spirv::PEM_COMPOSITE_VERT,
            fragment_spirv: fragment,
            vertex_bindings: &[],
            vertex_attributes: &[],
            color_formats: &[TARGET_FORMAT],
            depth_format: vk::Format::UNDEFINED,
            cull_mode: vk::CullModeFlags::NONE,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_constant_size: size_of::<RelightPush>() as u32,
            bindings: &[
                vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            ],
            blend: crate::backend::Blend::Replace,
            depth: DepthTest::Off,
            stencil: StencilTest::Off,
        },
    )
}
