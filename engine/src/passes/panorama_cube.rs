//! `panorama_cube`: level 0 of every face of a reflector's static EM from
//! the relit cylindrical panorama (`shaders/panorama_cube.frag`), so the
//! mirror pass shows the room under the moving light (`--light-path`); the
//! MIP passes after it filter the levels below.

use super::em_capture::CubeTarget;
use super::relight::draw_fullscreen;
use crate::backend::{
    Binding, Blend, DepthTest, Device, Filtering, GpuResult, Image, Pipeline, PipelineDesc,
    Sampler, StencilTest,
};
use crate::cube::{FACE_COUNT, face_axes};
use crate::graph::{Access, Pass, Usage};
use crate::shader_interface::{PanoramaCubePush, spirv};
use ash::vk;

/// The pipeline and the panorama's binding.
pub struct PanoramaCube {
    device: Device,
    pipeline: Pipeline,
    _sampler: Sampler,
    set: vk::DescriptorSet,
}

impl PanoramaCube {
    /// Reads `panorama` (sampled bilinearly, wrapping across the seam)
    /// into cubes of `format`.
    pub fn new(device: &Device, panorama: &Image, format: vk::Format) -> GpuResult<Self> {
        let pipeline = Pipeline::new(
            device,
            &PipelineDesc {
                name: "panorama_cube",
                vertex_spirv: spirv::PEM_COMPOSITE_VERT,
                fragment_spirv: spirv::PANORAMA_CUBE_FRAG,
                vertex_bindings: &[],
                vertex_attributes: &[],
                color_formats: &[format],
                depth_format: vk::Format::UNDEFINED,
                cull_mode: vk::CullModeFlags::NONE,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                push_constant_size: size_of::<PanoramaCubePush>() as u32,
                bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
                blend: Blend::Replace,
                depth: DepthTest::Off,
                stencil: StencilTest::Off,
            },
        )?;
        let sampler = Sampler::new(device, vk::SamplerAddressMode::REPEAT, Filtering::Bilinear)?;
        let set = pipeline.descriptor_set(&[Binding::Image(panorama.view, sampler.raw)])?;
        Ok(Self {
            device: device.clone(),
            pipeline,
            _sampler: sampler,
            set,
        })
    }

    pub fn pass<'a>(&'a self, panorama: &'a Image, cube: &'a CubeTarget) -> PanoramaCubePass<'a> {
        PanoramaCubePass {
            r: self,
            panorama,
            cube,
        }
    }
}

pub struct PanoramaCubePass<'a> {
    r: &'a PanoramaCube,
    panorama: &'a Image,
    cube: &'a CubeTarget,
}

impl Pass for PanoramaCubePass<'_> {
    fn name(&self) -> &str {
        "panorama_cube"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![
            Access::level(&self.cube.color, 0, Usage::ColorTarget),
            Access::whole(self.panorama, Usage::Sampled),
        ]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let size = self.cube.color.desc.width;
        for face in 0..FACE_COUNT {
            let [sc, tc, ma] = face_axes(face);
            let push = PanoramaCubePush {
                sc: sc.extend(size as f32),
                tc: tc.extend(0.0),
                ma: ma.extend(0.0),
            };
            let view = self.cube.color.target_view(0, face)?;
            let draw = (&self.r.pipeline, self.r.set);
            draw_fullscreen(&self.r.device, cmd, view, (size, size), draw, &push)?;
        }
        Ok(())
    }
}
