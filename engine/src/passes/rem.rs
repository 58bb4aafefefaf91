//! Reflection-space IBR on the device: the source maps (one 2D array),
//! the `rem_warp` pass that warps the current view's three source maps
//! into one sphere map — a disk tessellated finer toward the rim, drawn
//! once per source with additive blending, each weighted by its spherical
//! barycentric weight and faded near its singularity (alpha carries the
//! weight total) — and the `rem` pass that shades the reflector from it
//! per pixel.

use super::target::{Target, draw_mesh};
use crate::backend::upload::upload_image;
use crate::backend::{
    Binding, Blend, Buffer, DepthTest, Device, Filtering, GpuResult, Image, ImageDesc, Pipeline,
    PipelineDesc, Sampler, StencilTest,
};
use crate::gpu_scene::GpuScene;
use crate::graph::{Access, Executor, Pass, Usage};
use crate::shader_interface::{
    DISK_ATTRIBUTES, DISK_BINDING, REM_ATTRIBUTES, RemPush, RemWarpPush, Vertex, spirv,
};
use ash::vk;
use glam::{Mat3, Mat4, Vec2, Vec3};
use half::f16;

const MAP_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
const MAP_DEPTH: vk::Format = vk::Format::D32_SFLOAT;
/// Rings of the warp disk (uniform in reflection angle, so finer toward
/// the rim in the map) and segments around it.
const RINGS: u32 = 16;
const SEGMENTS: u32 = 48;

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
    /// Index of the reflector in `scene.objects`.
    pub object: usize,
}

/// Everything a REM frame needs on the device.
pub struct RemRenderer {
    device: Device,
    warp: Pipeline,
    shade: Pipeline,
    sources: Image,
    blended: Image,
    blended_depth: Image,
    disk: Buffer,
    disk_indices: Buffer,
    disk_index_count: u32,
    _sampler: Sampler,
    warp_set: vk::DescriptorSet,
    shade_set: vk::DescriptorSet,
    /// Index of the reflector in `scene.objects`.
    pub object: usize,
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
        let (points, indices) = disk_mesh();
        let points: Vec<[f32; 2]> = points.iter().map(|p| p.to_array()).collect();
        let disk = Buffer::with_data(
            device,
            "rem disk",
            vk::BufferUsageFlags::VERTEX_BUFFER,
            &points,
        )?;
        let disk_indices = Buffer::with_data(
            device,
            "rem disk",
            vk::BufferUsageFlags::INDEX_BUFFER,
            &indices,
        )?;
        let warp = pipeline(device, Stage::Warp, (MAP_FORMAT, MAP_DEPTH))?;
        let shade = pipeline(device, Stage::Shade, (color_format, depth_format))?;
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
            sources,
            blended,
            blended_depth,
            disk,
            disk_indices,
            disk_index_count: indices.len() as u32,
            _sampler: sampler,
            warp_set,
            shade_set,
            object: maps.object,
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
                axis_x: dest.col(0).extend(0.0),
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
    // The disk is drawn whole; the reflector's back faces are culled, as
    // the mirror pass does.
    let (name, vs, fs, bindings, attributes, push, blend, depth, cull) = match stage {
        Stage::Warp => (
            "rem_warp",
            spirv::REM_WARP_VERT,
            spirv::REM_WARP_FRAG,
            [DISK_BINDING],
            &DISK_ATTRIBUTES[..],
            size_of::<RemWarpPush>(),
            Blend::Add,
            DepthTest::Off,
            vk::CullModeFlags::NONE,
        ),
        Stage::Shade => (
            "rem",
            spirv::REM_VERT,
            spirv::REM_FRAG,
            [Vertex::BINDING],
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
            vertex_bindings: &bindings,
            vertex_attributes: attributes,
            color_formats: &[formats.0],
            depth_format: formats.1,
            cull_mode: cull,
            push_constant_size: push as u32,
            bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
            blend,
            depth,
            stencil: StencilTest::Off,
        },
    )
}

/// The warp disk: the centre, then `RINGS` rings of `SEGMENTS` points at
/// reflection angles `α = π k / RINGS` (radius `sin(α/2)` in the map, so
/// the rings crowd toward the rim where the warp bends most).
pub fn disk_mesh() -> (Vec<Vec2>, Vec<u32>) {
    let mut points = vec![Vec2::splat(0.5)];
    for k in 1..=RINGS {
        let rho = (std::f32::consts::PI * k as f32 / RINGS as f32 / 2.0).sin();
        for s in 0..SEGMENTS {
            let phi = std::f32::consts::TAU * s as f32 / SEGMENTS as f32;
            points.push(Vec2::splat(0.5) + 0.5 * rho * Vec2::new(phi.cos(), phi.sin()));
        }
    }
    let at = |k: u32, s: u32| 1 + (k - 1) * SEGMENTS + s % SEGMENTS;
    let mut indices = Vec::new();
    for s in 0..SEGMENTS {
        indices.extend([0, at(1, s), at(1, s + 1)]);
    }
    for k in 1..RINGS {
        for s in 0..SEGMENTS {
            let (a, b, c, d) = (at(k, s), at(k, s + 1), at(k + 1, s), at(k + 1, s + 1));
            indices.extend([a, c, b, b, c, d]);
        }
    }
    (points, indices)
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
            for draw in &self.draws {
                let push = RemWarpPush {
                    dest_to_source: Mat4::from_mat3(draw.frame.transpose() * self.dest),
                    info: glam::Vec4::new(draw.weight, draw.layer as f32, FADE_COS.1, FADE_COS.0),
                };
                r.warp.bind(cmd, Some(r.warp_set), &push)?;
                // SAFETY: the warp pipeline is bound inside dynamic
                // rendering; the disk buffers hold disk_index_count indices
                // of points they hold.
                unsafe {
                    let d = &r.device.device;
                    d.cmd_bind_vertex_buffers(cmd, 0, &[r.disk.raw], &[0]);
                    d.cmd_bind_index_buffer(cmd, r.disk_indices.raw, 0, vk::IndexType::UINT32);
                    d.cmd_draw_indexed(cmd, r.disk_index_count, 1, 0, 0, 0);
                }
            }
            Ok(())
        })
    }
}

impl<'a> RemWarpPass<'a> {
    fn target(&self) -> Target<'a> {
        Target {
            color: &self.r.blended,
            depth: &self.r.blended_depth,
            level: 0,
            layer: 0,
            clear: true,
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
            if let Some(mesh) = self.gpu.meshes.get(r.object) {
                draw_mesh(&r.device, cmd, mesh, None);
            }
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disk_rings_crowd_toward_the_rim_and_stay_inside() {
        let (points, indices) = disk_mesh();
        assert_eq!(points.len() as u32, 1 + RINGS * SEGMENTS);
        assert!(indices.iter().all(|&i| (i as usize) < points.len()));
        let radius =
            |k: u32| (points[(1 + (k - 1) * SEGMENTS) as usize] - Vec2::splat(0.5)).length();
        assert!((radius(RINGS) - 0.5).abs() < 1e-6);
        let inner = radius(2) - radius(1);
        let outer = radius(RINGS) - radius(RINGS - 1);
        assert!(outer < inner / 10.0, "{inner} {outer}");
        assert!(
            points
                .iter()
                .all(|p| (*p - Vec2::splat(0.5)).length() <= 0.5 + 1e-6)
        );
    }
}
