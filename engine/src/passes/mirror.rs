//! Mirror reflectors shaded from a cube environment map indexed by CPU
//! texgen, times Schlick Fresnel read through a 1D LUT of (1 − cos)^5.

use super::target::{Target, draw_mesh};
use crate::backend::upload::upload_image;
use crate::backend::{
    Binding, Buffer, Device, GpuResult, Image, ImageDesc, Pipeline, PipelineDesc, Sampler,
};
use crate::gpu_scene::GpuScene;
use crate::graph::{Access, Executor, Pass, Usage};
use crate::shader_interface::{MIRROR_ATTRIBUTES, MirrorPush, TEXGEN_BINDING, Vertex, spirv};
use ash::vk;
use glam::Mat4;

/// Texels of the Fresnel LUT; texel i holds (1 − i/(N−1))^5 so both ends
/// (normal incidence and exactly 90°) are exact.
pub const FRESNEL_LUT_SIZE: u32 = 256;

pub fn fresnel_lut() -> Vec<f32> {
    let n = FRESNEL_LUT_SIZE;
    (0..n)
        .map(|i| (1.0 - i as f32 / (n - 1) as f32).powi(5))
        .collect()
}

/// The mirror pipeline; probe renders build it with this same function.
pub fn mirror_pipeline(
    device: &Device,
    color_format: vk::Format,
    depth_format: vk::Format,
) -> GpuResult<Pipeline> {
    Pipeline::new(
        device,
        &PipelineDesc {
            name: "mirror",
            vertex_spirv: spirv::MIRROR_VERT,
            fragment_spirv: spirv::MIRROR_FRAG,
            vertex_bindings: &[Vertex::BINDING, TEXGEN_BINDING],
            vertex_attributes: &MIRROR_ATTRIBUTES,
            color_formats: &[color_format],
            depth_format,
            cull_mode: vk::CullModeFlags::BACK,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_constant_size: size_of::<MirrorPush>() as u32,
            bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER; 2],
            blend: crate::backend::Blend::Replace,
            depth: crate::backend::DepthTest::TestWrite,
            stencil: crate::backend::StencilTest::Off,
        },
    )
}

/// The Fresnel LUT as a 1D R32F image, uploaded and ready to sample.
pub fn fresnel_lut_image(device: &Device, executor: &mut Executor) -> GpuResult<Image> {
    let lut = Image::new(
        device,
        "fresnel lut",
        ImageDesc::new_1d(vk::Format::R32_SFLOAT, FRESNEL_LUT_SIZE)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    upload_image(
        device,
        executor.commands(),
        &lut,
        bytemuck::cast_slice(&fresnel_lut()),
    )?;
    executor.states.assume(&lut, Usage::Sampled);
    Ok(lut)
}

/// One reflective object: its mesh, F0, its per-frame texgen buffer and
/// the environment map it samples.
pub struct MirrorDraw {
    pub object: usize,
    pub f0: glam::Vec3,
    pub texgen: Buffer,
    set: vk::DescriptorSet,
}

pub struct MirrorRenderer {
    device: Device,
    pipeline: Pipeline,
    /// The reflectors' insides, black (`super::interior`).
    interior: Pipeline,
    lut: Image,
    lut_sampler: Sampler,
    cube_sampler: Sampler,
}

impl MirrorRenderer {
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        color_format: vk::Format,
        depth_format: vk::Format,
    ) -> GpuResult<Self> {
        let pipeline = mirror_pipeline(device, color_format, depth_format)?;
        let interior = super::interior::black_interior(device, color_format, depth_format)?;
        let lut = fresnel_lut_image(device, executor)?;
        Ok(Self {
            device: device.clone(),
            pipeline,
            interior,
            lut,
            lut_sampler: Sampler::trilinear(device, vk::SamplerAddressMode::CLAMP_TO_EDGE)?,
            cube_sampler: Sampler::trilinear(device, vk::SamplerAddressMode::CLAMP_TO_EDGE)?,
        })
    }

    /// A draw of `object` (with `vertex_count` vertices) sampling `cube`.
    pub fn draw_for(
        &self,
        object: usize,
        vertex_count: usize,
        f0: glam::Vec3,
        cube: &Image,
    ) -> GpuResult<MirrorDraw> {
        let texgen = Buffer::new(
            &self.device,
            "texgen",
            (vertex_count * 16) as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER,
            gpu_allocator::MemoryLocation::CpuToGpu,
        )?;
        let set = self.pipeline.descriptor_set(&[
            Binding::Image(cube.view, self.cube_sampler.raw),
            Binding::Image(self.lut.view, self.lut_sampler.raw),
        ])?;
        Ok(MirrorDraw {
            object,
            f0,
            texgen,
            set,
        })
    }

    pub fn pass<'a>(
        &'a self,
        gpu: &'a GpuScene,
        draws: Vec<&'a MirrorDraw>,
        cubes: Vec<&'a Image>,
        target: Target<'a>,
        view_proj: Mat4,
    ) -> MirrorPass<'a> {
        MirrorPass {
            renderer: self,
            gpu,
            draws,
            cubes,
            target,
            view_proj,
        }
    }
}

/// Draws the reflectors over what the room pass left in the target.
pub struct MirrorPass<'a> {
    renderer: &'a MirrorRenderer,
    gpu: &'a GpuScene,
    draws: Vec<&'a MirrorDraw>,
    cubes: Vec<&'a Image>,
    target: Target<'a>,
    view_proj: Mat4,
}

impl Pass for MirrorPass<'_> {
    fn name(&self) -> &str {
        "mirror"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        let mut sampled = vec![&self.renderer.lut];
        sampled.extend(self.cubes.iter().copied());
        self.target.accesses(&sampled)
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let r = self.renderer;
        self.target.render(&r.device, cmd, || {
            for draw in &self.draws {
                let push = MirrorPush {
                    view_proj: self.view_proj,
                    f0: draw.f0.extend(0.0),
                };
                r.pipeline.bind(cmd, Some(draw.set), &push)?;
                if let Some(mesh) = self.gpu.meshes.get(draw.object) {
                    draw_mesh(&r.device, cmd, mesh, Some(&draw.texgen));
                }
            }
            // The insides (caps over openings) after the front faces.
            let caps = self
                .draws
                .iter()
                .filter_map(|d| self.gpu.caps.get(d.object));
            super::interior::record_caps(
                &r.device,
                cmd,
                &r.interior,
                self.view_proj,
                caps.flatten(),
            )?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn lut_ends_are_exact_and_match_schlick() {
        let lut = fresnel_lut();
        assert_eq!(lut[0], 1.0);
        assert_eq!(lut[lut.len() - 1], 0.0);
        let f0 = Vec3::splat(0.04);
        let i = 100;
        let cos = i as f32 / (FRESNEL_LUT_SIZE - 1) as f32;
        let from_lut = f0 + (Vec3::ONE - f0) * lut[i];
        let reference = inference::scene::schlick_fresnel(f0, cos);
        assert!((from_lut - reference).abs().max_element() < 1e-6);
    }
}
