//! The diffuse room (and emitters): Lambertian with the baked procedural
//! textures, lit by the area light as a point emitter plus ambient. Also
//! the "bare" variant: every mesh with one texture, nothing else.

use super::target::{Target, draw_mesh};
use crate::backend::{Binding, Buffer, Device, GpuResult, Pipeline, PipelineDesc};
use crate::gpu_scene::GpuScene;
use crate::graph::{Access, Pass};
use crate::shader_interface::{RoomLight, RoomPush, Vertex, spirv};
use ash::vk;
use glam::{Mat4, Vec4};
use inference::scene::{Material, Scene};

struct Draw {
    object: usize,
    set: vk::DescriptorSet,
    push: RoomPush,
}

/// Owns the room pipeline and one draw per diffuse or emissive object.
pub struct RoomRenderer {
    device: Device,
    pipeline: Pipeline,
    draws: Vec<Draw>,
    /// The `Light` uniform block, constant for the scene.
    _light: Buffer,
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub enum RoomStyle {
    /// Lit diffuse room and emitters (reflectors are drawn by their passes).
    Lit,
    /// Every object, one texture, no lighting: the bare reference pass.
    Bare,
}

impl RoomRenderer {
    pub fn new(
        device: &Device,
        scene: &Scene,
        gpu: &GpuScene,
        style: RoomStyle,
        color_format: vk::Format,
        depth_format: vk::Format,
    ) -> GpuResult<Self> {
        let pipeline = room_pipeline(device, style, color_format, depth_format)?;
        let light = Buffer::with_data(
            device,
            "room light",
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            &[room_lighting(scene)],
        )?;
        let first_texture = scene.textures.first().map(|_| 0);
        let mut draws = Vec::new();
        for (object, o) in scene.objects.iter().enumerate() {
            let material = scene.materials.get(o.material);
            let (albedo, emission, texture) = match (style, material) {
                (RoomStyle::Bare, _) => (Vec4::ONE, Vec4::ZERO, first_texture),
                (_, Some(Material::Diffuse { albedo, texture })) => {
                    let textured = if texture.is_some() { 1.0 } else { 0.0 };
                    (albedo.extend(textured), Vec4::ZERO, *texture)
                }
                (_, Some(Material::Emissive { radiance })) => {
                    (Vec4::ZERO, radiance.extend(0.0), None)
                }
                _ => continue, // reflectors and glass have their own passes
            };
            let image = gpu.texture(texture);
            let set = pipeline.descriptor_set(&[
                Binding::Image(image.view, gpu.sampler.raw),
                Binding::Uniform(&light),
            ])?;
            draws.push(Draw {
                object,
                set,
                push: RoomPush {
                    albedo,
                    emission,
                    ..RoomPush::default()
                },
            });
        }
        Ok(Self {
            device: device.clone(),
            pipeline,
            draws,
            _light: light,
        })
    }

    pub fn device(&self) -> &Device {
        &self.device
    }

    /// Records every draw with `view_proj` inside the current rendering.
    pub fn draw(&self, cmd: vk::CommandBuffer, gpu: &GpuScene, view_proj: Mat4) -> GpuResult<()> {
        for draw in &self.draws {
            let push = RoomPush {
                view_proj,
                ..draw.push
            };
            self.pipeline.bind(cmd, Some(draw.set), &push)?;
            if let Some(mesh) = gpu.meshes.get(draw.object) {
                draw_mesh(&self.device, cmd, mesh, None);
            }
        }
        Ok(())
    }

    pub fn pass<'a>(
        &'a self,
        name: &'static str,
        gpu: &'a GpuScene,
        target: Target<'a>,
        view_proj: Mat4,
    ) -> RoomPass<'a> {
        RoomPass {
            name,
            renderer: self,
            gpu,
            target,
            view_proj,
        }
    }
}

/// The room (lit) or bare pipeline. Probe renders build the bare one with
/// this same function, so they sample exactly as playback does.
pub fn room_pipeline(
    device: &Device,
    style: RoomStyle,
    color_format: vk::Format,
    depth_format: vk::Format,
) -> GpuResult<Pipeline> {
    let (name, fragment_spirv) = match style {
        RoomStyle::Lit => ("room", spirv::ROOM_FRAG),
        RoomStyle::Bare => ("bare", spirv::BARE_FRAG),
    };
    Pipeline::new(
        device,
        &PipelineDesc {
            name,
            vertex_spirv: spirv::ROOM_VERT,
            fragment_spirv,
            vertex_bindings: &[Vertex::BINDING],
            vertex_attributes: &Vertex::ATTRIBUTES,
            color_formats: &[color_format],
            depth_format,
            cull_mode: vk::CullModeFlags::BACK,
            push_constant_size: size_of::<RoomPush>() as u32,
            bindings: &[
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                vk::DescriptorType::UNIFORM_BUFFER,
            ],
            blend_by_alpha: false,
            depth: crate::backend::DepthTest::TestWrite,
            stencil: crate::backend::StencilTest::Off,
        },
    )
}

/// The light shared by every room draw: the first area light as a point
/// emitter at its centre, and an ambient term standing in for the indirect
/// light (radiance ≈ ρ/(1 − ρ) · light area / room area · L for ρ = ½).
fn room_lighting(scene: &Scene) -> RoomLight {
    let Some(light) = scene.lights.first() else {
        return RoomLight::default();
    };
    let (lo, hi) = scene.bounds();
    let size = hi - lo;
    let room_area = 2.0 * (size.x * size.y + size.y * size.z + size.z * size.x);
    let ambient = if room_area > 0.0 {
        light.area() / room_area
    } else {
        0.0
    };
    RoomLight {
        center: light.center.extend(light.area()),
        normal: light.normal().extend(ambient),
        radiance: light.radiance.extend(0.0),
    }
}

/// Draws the room into a target (clearing it first if the target says so).
pub struct RoomPass<'a> {
    name: &'static str,
    renderer: &'a RoomRenderer,
    gpu: &'a GpuScene,
    target: Target<'a>,
    view_proj: Mat4,
}

impl Pass for RoomPass<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.target.accesses(&[])
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        self.target.render(&self.renderer.device, cmd, || {
            self.renderer.draw(cmd, self.gpu, self.view_proj)
        })
    }
}
