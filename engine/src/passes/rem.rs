//! Reflection-space IBR on the device: the source maps (one 2D array),
//! the `rem_warp` pass that warps the current view's three source maps
//! into one sphere map — one full-screen pass over its texels, each
//! source read where the texel's reflection direction falls in it,
//! weighted by its spherical barycentric weight and faded near its
//! singularity (alpha carries the weight total) — and the `rem` pass that
//! shades the reflector from it per pixel.

use super::target::{Load, Target, draw_mesh};
use crate::backend::upload::upload_image;
use crate::backend::{
    Binding, Blend, DepthTest, Device, Filtering, GpuResult, Image, ImageDesc, Pipeline,
    PipelineDesc, Sampler, StencilTest,
};
use crate::gpu_scene::GpuScene;
use crate::graph::{Access, Executor, Pass, Usage};
use crate::shader_interface::{REM_ATTRIBUTES, RemPush, RemWarpPush, Vertex, spirv};
use ash::vk;
use glam::{Mat3, Mat4, Quat, Vec3, Vec4};
use half::f16;

const MAP_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
const MAP_DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// Where a source's weight fades: full while the cosine of the angle
/// between a reflection direction and the source's singularity (straight
/// behind the source view) is below `.0` (60°), almost nothing above `.1`
/// (15°), where the source's sphere map pinches into its rim.
pub const FADE_COS: (f32, f32) = (0.5, 0.966);

/// One source map's part of the blended map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarpDraw {
    /// The source's camera frame `T_s`.
    pub frame: Mat3,
    /// Its spherical barycentric weight.
    pub weight: f32,
    /// Its layer in the source array.
    pub layer: u32,
}

/// The source maps as uploaded: `count` RGBA maps of `size`², map-major.
pub struct SourceTexels<'a> {
    pub size: u32,
    pub count: u32,
    pub texels: &'a [[f32; 4]],
    /// The reflector's parts, indices in `scene.objects` (lid and body).
    pub parts: Vec<usize>,
    /// Warp by the normal (a diffuse reflector), not the mirror direction.
    pub normal_warp: bool,
}

/// Everything a REM frame needs on the device.
pub struct RemRenderer {
    device: Device,
    warp: Pipeline,
    shade: Pipeline,
    /// The reflector's inside, black (`super::interior`).
    interior: Pipeline,
    sources: Image,
    blended: Image,
    blended_depth: Image,
    _sampler: Sampler,
    warp_set: vk::DescriptorSet,
    shade_set: vk::DescriptorSet,
    /// The reflector's parts, indices in `scene.objects`.
    pub parts: Vec<usize>,
    /// The maps are warped and read by the normal (`SourceTexels`).
    pub normal_warp: bool,
}

impl RemRenderer {
    /// Uploads `maps` and makes the blended map (`size`², like a source).
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        maps: &SourceTexels,
        (color_format, depth_format): (vk::Format, vk::Format),
    ) -> GpuResult<Self> {
        let count = maps.count;
        let sources = Image::new(
            device,
            "rem sources",
            ImageDesc::new_2d_array(MAP_FORMAT, maps.size, maps.size, count)
                .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
        )?;
        let halves: Vec<f16> = maps
            .texels
            .iter()
            .flatten()
            .map(|&x| f16::from_f32(x))
            .collect();
        upload_image(
            device,
            executor.commands(),
            &sources,
            bytemuck::cast_slice(&halves),
        )?;
        executor.states.assume(&sources, Usage::Sampled);
        let blended = Image::new(
            device,
            "rem blended map",
            ImageDesc::new_2d(MAP_FORMAT, maps.size, maps.size).usage(
                vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_SRC,
            ),
        )?;
        let blended_depth = Image::new(
            device,
            "rem blended depth",
            ImageDesc::new_2d(MAP_DEPTH, maps.size, maps.size)
                .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        let warp = pipeline(device, Stage::Warp, (MAP_FORMAT, MAP_DEPTH))?;
        let shade = pipeline(device, Stage::Shade, (color_format, depth_format))?;
        let interior = super::interior::black_interior(device, color_format, depth_format)?;
        let sampler = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            Filtering::Bilinear,
        )?;
        let warp_set = warp.descriptor_set(&[Binding::Image(sources.view, sampler.raw)])?;
        let shade_set = shade.descriptor_set(&[Binding::Image(blended.view, sampler.raw)])?;
        Ok(Self {
            device: device.clone(),
            warp,
            shade,
            interior,
            sources,
            blended,
            blended_depth,
            _sampler: sampler,
            warp_set,
            shade_set,
            parts: maps.parts.clone(),
            normal_warp: maps.normal_warp,
        })
    }

    /// The blended map of the last frame (for read-back).
    pub fn blended(&self) -> &Image {
        &self.blended
    }

    /// The pass that warps and blends `draws` into the blended map, seen
    /// in frame `dest`.
    pub fn warp_pass(&self, dest: Mat3, draws: Vec<WarpDraw>) -> RemWarpPass<'_> {
        RemWarpPass {
            r: self,
            dest,
            draws,
        }
    }

    /// The pass that draws the reflector into `target` from the blended
    /// map, whose frame is `dest`.
    pub fn shade_pass<'a>(
        &'a self,
        gpu: &'a GpuScene,
        target: Target<'a>,
        view_proj: Mat4,
        eye: Vec3,
        dest: Mat3,
    ) -> RemPass<'a> {
        RemPass {
            r: self,
            gpu,
            target,
            push: RemPush {
                view_proj,
                eye: eye.extend(1.0),
                axis_x: dest.col(0).extend(f32::from(u8::from(self.normal_warp))),
                axis_y: dest.col(1).extend(0.0),
                axis_z: dest.col(2).extend(0.0),
            },
        }
    }
}

#[derive(Clone, Copy)]
enum Stage {
    Warp,
    Shade,
}

fn pipeline(
    device: &Device,
    stage: Stage,
    formats: (vk::Format, vk::Format),
) -> GpuResult<Pipeline> {
    // The warp is one full-screen triangle; the reflector's back faces are
    // culled, as the mirror pass does.
    let (name, vs, fs, bindings, attributes, push, blend, depth, cull) = match stage {
        Stage::Warp => (
            "rem_warp",
            spirv::PEM_COMPOSITE_VERT,
            spirv::REM_WARP_FRAG,
            &[][..],
            &[][..],
            size_of::<RemWarpPush>(),
            Blend::Replace,
            DepthTest::Off,
            vk::CullModeFlags::NONE,
        ),
        Stage::Shade => (
            "rem",
            spirv::REM_VERT,
            spirv::REM_FRAG,
            &[Vertex::BINDING][..],
            &REM_ATTRIBUTES[..],
            size_of::<RemPush>(),
            Blend::Replace,
            DepthTest::TestWrite,
            vk::CullModeFlags::BACK,
        ),
    };
    Pipeline::new(
        device,
        &PipelineDesc {
            name,
            vertex_spirv: vs,
            fragment_spirv: fs,
            vertex_bindings: bindings,
            vertex_attributes: attributes,
            color_formats: &[formats.0],
            depth_format: formats.1,
            cull_mode: cull,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_constant_size: push as u32,
            bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
            blend,
            depth,
            stencil: StencilTest::Off,
        },
    )
}

/// `rem_warp`: the three (or one) source maps warped into the blended map.
pub struct RemWarpPass<'a> {
    r: &'a RemRenderer,
    dest: Mat3,
    draws: Vec<WarpDraw>,
}

impl Pass for RemWarpPass<'_> {
    fn name(&self) -> &str {
        "rem_warp"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.target().accesses(&[&self.r.sources])
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let r = self.r;
        self.target().render(&r.device, cmd, || {
            r.warp.bind(
                cmd,
                Some(r.warp_set),
                &warp_push(self.dest, &self.draws, r.normal_warp),
            )?;
            // SAFETY: the warp pipeline is bound inside dynamic rendering;
            // its vertex shader makes the full-screen triangle from the
            // vertex index, no buffers bound.
            unsafe { r.device.device.cmd_draw(cmd, 3, 1, 0, 0) };
            Ok(())
        })
    }
}

/// The warp's push constants: each source's rotation from the destination
/// frame `dest` as a quaternion of `T_s⁻¹ T_d`, its weight and layer (at
/// most three sources; absent ones weigh 0), and which warp (`fade.z` = 1:
/// by the normal).
pub fn warp_push(dest: Mat3, draws: &[WarpDraw], normal_warp: bool) -> RemWarpPush {
    let mut push = RemWarpPush {
        fade: Vec4::new(
            FADE_COS.1,
            FADE_COS.0,
            f32::from(u8::from(normal_warp)),
            0.0,
        ),
        ..Default::default()
    };
    for (i, draw) in draws.iter().take(3).enumerate() {
        // Both frames are rotations (right-handed orthonormal, `view_frame`).
        push.rotation[i] = Vec4::from(Quat::from_mat3(&(draw.frame.transpose() * dest)));
        push.weight[i] = draw.weight;
        push.layer[i] = draw.layer as f32;
    }
    push
}

impl<'a> RemWarpPass<'a> {
    fn target(&self) -> Target<'a> {
        Target {
            color: &self.r.blended,
            depth: &self.r.blended_depth,
            level: 0,
            layer: 0,
            load: Load::Clear,
            front_face: vk::FrontFace::COUNTER_CLOCKWISE,
            area: None,
        }
    }
}

/// `rem`: the reflector shaded from the blended map.
pub struct RemPass<'a> {
    r: &'a RemRenderer,
    gpu: &'a GpuScene,
    target: Target<'a>,
    push: RemPush,
}

impl Pass for RemPass<'_> {
    fn name(&self) -> &str {
        "rem"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.target.accesses(&[&self.r.blended])
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let r = self.r;
        self.target.render(&r.device, cmd, || {
            r.shade.bind(cmd, Some(r.shade_set), &self.push)?;
            for mesh in r.parts.iter().filter_map(|&o| self.gpu.meshes.get(o)) {
                draw_mesh(&r.device, cmd, mesh, None);
            }
            // Their insides (caps over their openings) after the front faces.
            let caps =
                (r.parts.iter()).filter_map(|&o| self.gpu.caps.get(o).and_then(Option::as_ref));
            super::interior::record_caps(&r.device, cmd, &r.interior, self.push.view_proj, caps)?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_warp_push_rotates_as_the_frames_do() {
        use crate::rem::geometry::view_frame;
        let dest = view_frame(Vec3::new(0.3, 0.2, 1.0));
        let draws: Vec<WarpDraw> = [Vec3::new(-0.4, 0.5, 0.8), Vec3::Y, Vec3::NEG_Z]
            .iter()
            .enumerate()
            .map(|(i, &v)| WarpDraw {
                frame: view_frame(v),
                weight: 0.2 * (i + 1) as f32,
                layer: i as u32 + 4,
            })
            .collect();
        let push = warp_push(dest, &draws, false);
        let v = Vec3::new(0.48, -0.6, 0.64);
        for (i, d) in draws.iter().enumerate() {
            let q = Quat::from_vec4(push.rotation[i]);
            let want = d.frame.transpose() * dest * v;
            assert!((q * v - want).length() < 1e-5, "source {i}");
            assert_eq!(push.weight[i], d.weight);
            assert_eq!(push.layer[i], d.layer as f32);
        }
        let one = warp_push(dest, &draws[..1], true);
        assert_eq!(one.fade.z, 1.0, "normal warp flag");
        assert_eq!(
            (one.weight[1], one.weight[2]),
            (0.0, 0.0),
            "absent sources weigh 0"
        );
    }
}
