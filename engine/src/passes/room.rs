//! The diffuse room (and emitters): Lambertian with the procedural
//! textures, lit either by the area light as a point emitter plus ambient
//! (the analytic room, which reads them baked) or by each object's inferred
//! light map (the traced light: `compile::room`; patterns drawn in closed
//! form, `room_albedo`). Also the "bare" variant: every mesh with one
//! texture, nothing else.

use super::room_albedo::{PATTERN_VARIANTS, SurfaceAlbedo};
use super::room_maps::GpuRoomMap;
use super::target::{Target, draw_mesh};
use crate::backend::{Binding, Buffer, Device, GpuResult, Pipeline, PipelineDesc};
use crate::gpu_scene::GpuScene;
use crate::graph::{Access, Pass};
use crate::shader_interface::{
    LIGHT_UV_BINDING, ROOM_INFERRED_ATTRIBUTES, RoomLight, RoomPush, Vertex, spirv,
};
use ash::vk;
use glam::{Mat4, Vec4};
use inference::scene::{Material, Scene};

struct Draw {
    object: usize,
    set: vk::DescriptorSet,
    push: RoomPush,
    /// The pipeline variant: how the albedo is drawn (`room_albedo`).
    variant: usize,
    /// The light-map coordinates (index into `light_uvs`), inferred room only.
    light_uvs: Option<usize>,
}

/// Owns the room pipeline and one draw per diffuse or emissive object.
pub struct RoomRenderer {
    device: Device,
    pipeline: Pipeline,
    draws: Vec<Draw>,
    /// The `Light` uniform block: the scene's, or a moving light's
    /// ([`RoomRenderer::set_light`]).
    light: Buffer,
    /// Inferred room: the light maps, and per drawn object without one a
    /// zero coordinate stream (so the second vertex binding is always bound).
    _maps: Vec<(usize, crate::backend::Image)>,
    light_uvs: Vec<Buffer>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub enum RoomStyle {
    /// Lit diffuse room and emitters (reflectors are drawn by their passes).
    Lit,
    /// Every object, one texture, no lighting: the bare reference pass.
    Bare,
    /// Diffuse room from inferred light maps (`compile::room`), emitters.
    Inferred,
    /// The albedo alone, as the inferred room draws it: the light-map
    /// solve's known factor (probe renders).
    Albedo,
}

/// What a room draw of `o` pushes under `style`: albedo, emission and the
/// texture (white when none); None for objects other passes draw.
fn material_of(
    style: RoomStyle,
    scene: &Scene,
    o: &inference::scene::Object,
) -> Option<(SurfaceAlbedo, Vec4, Option<usize>)> {
    let first_texture = scene.textures.first().map(|_| 0);
    match (style, scene.materials.get(o.material)) {
        // The bare pass reads one texture, whatever it was baked from.
        (RoomStyle::Bare, _) => Some((
            SurfaceAlbedo::of(glam::Vec3::ONE, None),
            Vec4::ZERO,
            first_texture,
        )),
        // The analytic room stays as the issue measured it (the static EM
        // frame's room and the inferred room's yardstick): texture reads.
        (RoomStyle::Lit, Some(Material::Diffuse { albedo, texture })) => {
            Some((SurfaceAlbedo::of(*albedo, None), Vec4::ZERO, *texture))
        }
        (_, Some(Material::Diffuse { albedo, texture })) => {
            let baked = texture.and_then(|t| scene.textures.get(t));
            Some((SurfaceAlbedo::of(*albedo, baked), Vec4::ZERO, *texture))
        }
        (_, Some(Material::Emissive { radiance })) => Some((
            SurfaceAlbedo::of(glam::Vec3::ZERO, None),
            radiance.extend(0.0),
            None,
        )),
        _ => None, // reflectors and glass have their own passes
    }
}

/// The push constants of a draw (its `view_proj` set when drawn).
fn push_of(albedo: SurfaceAlbedo, emission: Vec4) -> RoomPush {
    RoomPush {
        albedo: albedo.first,
        emission,
        pattern: albedo.second,
        ..RoomPush::default()
    }
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
        let mut draws = Vec::new();
        for (object, o) in scene.objects.iter().enumerate() {
            let Some((albedo, emission, texture)) = material_of(style, scene, o) else {
                continue;
            };
            let image = gpu.texture(texture);
            let set = pipeline.descriptor_set(&[
                Binding::Image(image.view, gpu.sampler.raw),
                Binding::Uniform(&light),
            ])?;
            draws.push(Draw {
                object,
                set,
                push: push_of(albedo, emission),
                variant: albedo.variant,
                light_uvs: None,
            });
        }
        if style == RoomStyle::Bare {
            // Reflectors and glass first, as the lit frames draw them: the
            // depth they lay down spares the room's shading behind them.
            let drawn_late = |d: &Draw| {
                matches!(
                    scene
                        .objects
                        .get(d.object)
                        .and_then(|o| scene.materials.get(o.material)),
                    Some(Material::Diffuse { .. } | Material::Emissive { .. })
                )
            };
            draws.sort_by_key(drawn_late);
        }
        Ok(Self {
            device: device.clone(),
            pipeline,
            draws,
            light,
            _maps: Vec::new(),
            light_uvs: Vec::new(),
        })
    }

    /// The room from inferred light maps (`maps`, uploaded): each diffuse
    /// object's albedo times its light map; an object without one (no view
    /// saw it) shows its albedo alone, emitters their emission.
    pub fn inferred(
        device: &Device,
        scene: &Scene,
        gpu: &GpuScene,
        maps: Vec<GpuRoomMap>,
        color_format: vk::Format,
        depth_format: vk::Format,
    ) -> GpuResult<Self> {
        let style = RoomStyle::Inferred;
        let pipeline = room_pipeline(device, style, color_format, depth_format)?;
        let light = Buffer::with_data(
            device,
            "room light",
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            &[RoomLight::default()],
        )?;
        let mut draws = Vec::new();
        let mut light_uvs = Vec::new();
        let mut uvs_of: std::collections::HashMap<usize, Buffer> = Default::default();
        let mut images = Vec::new();
        for m in maps {
            uvs_of.insert(m.object, m.uvs);
            images.push((m.object, m.image));
        }
        for (object, o) in scene.objects.iter().enumerate() {
            let Some((albedo, emission, texture)) = material_of(style, scene, o) else {
                continue;
            };
            let light_map = images
                .iter()
                .find(|(k, _)| *k == object)
                .map_or(&gpu.white, |(_, image)| image);
            let set = pipeline.descriptor_set(&[
                Binding::Image(gpu.texture(texture).view, gpu.sampler.raw),
                Binding::Image(light_map.view, gpu.light_sampler.raw),
            ])?;
            let light_uv = match uvs_of.remove(&object) {
                Some(uvs) => uvs,
                None => Buffer::with_data(
                    device,
                    "room light-map uvs (none)",
                    vk::BufferUsageFlags::VERTEX_BUFFER,
                    &vec![[0.5f32; 2]; o.mesh.positions.len().max(1)],
                )?,
            };
            light_uvs.push(light_uv);
            draws.push(Draw {
                object,
                set,
                push: push_of(albedo, emission),
                variant: albedo.variant,
                light_uvs: Some(light_uvs.len() - 1),
            });
        }
        Ok(Self {
            device: device.clone(),
            pipeline,
            draws,
            light,
            _maps: images,
            light_uvs,
        })
    }

    pub fn device(&self) -> &Device {
        &self.device
    }

    /// Lights the room with `light` from the next frame on (`--light-path`).
    pub fn set_light(&mut self, light: RoomLight) -> GpuResult<()> {
        let bytes = bytemuck::bytes_of(&light);
        // The engine waits for every frame's fence, so no frame reads the
        // block while it is written.
        self.light.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// Darkens the scene's emitters (a moving light replaces them).
    pub fn darken_emitters(&mut self) {
        for draw in &mut self.draws {
            draw.push.emission = Vec4::ZERO;
        }
    }

    /// Records every draw with `view_proj` inside the current rendering.
    pub fn draw(&self, cmd: vk::CommandBuffer, gpu: &GpuScene, view_proj: Mat4) -> GpuResult<()> {
        for draw in &self.draws {
            let push = RoomPush {
                view_proj,
                ..draw.push
            };
            self.pipeline
                .bind_variant(cmd, draw.variant, Some(draw.set), &push)?;
            if let Some(mesh) = gpu.meshes.get(draw.object) {
                let light_uvs = draw.light_uvs.and_then(|i| self.light_uvs.get(i));
                draw_mesh(&self.device, cmd, mesh, light_uvs);
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
    let (name, vertex_spirv, fragment_spirv) = match style {
        RoomStyle::Lit => ("room", spirv::ROOM_VERT, spirv::ROOM_FRAG),
        RoomStyle::Bare => ("bare", spirv::ROOM_VERT, spirv::BARE_FRAG),
        RoomStyle::Albedo => ("albedo", spirv::ROOM_VERT, spirv::ALBEDO_PROBE_FRAG),
        RoomStyle::Inferred => (
            "room inferred",
            spirv::ROOM_INFERRED_VERT,
            spirv::ROOM_INFERRED_FRAG,
        ),
    };
    let inferred = style == RoomStyle::Inferred;
    let (vertex_bindings, vertex_attributes): (&[_], &[_]) = if inferred {
        (
            &[Vertex::BINDING, LIGHT_UV_BINDING],
            &ROOM_INFERRED_ATTRIBUTES,
        )
    } else {
        (&[Vertex::BINDING], &Vertex::ATTRIBUTES)
    };
    let second = if inferred {
        vk::DescriptorType::COMBINED_IMAGE_SAMPLER
    } else {
        vk::DescriptorType::UNIFORM_BUFFER
    };
    // The inferred room and its albedo probe: one variant per albedo kind;
    // the bare and analytic rooms read textures (one shader each).
    let variants: &[u32] = if matches!(style, RoomStyle::Inferred | RoomStyle::Albedo) {
        &PATTERN_VARIANTS
    } else {
        &[]
    };
    Pipeline::with_variants(
        device,
        &PipelineDesc {
            name,
            vertex_spirv,
            fragment_spirv,
            vertex_bindings,
            vertex_attributes,
            color_formats: &[color_format],
            depth_format,
            cull_mode: vk::CullModeFlags::BACK,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            push_constant_size: size_of::<RoomPush>() as u32,
            bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER, second],
            blend: crate::backend::Blend::Replace,
            depth: crate::backend::DepthTest::TestWrite,
            // The deferred PEM frame marks its reflectors before the room:
            // a diffuse object drawn in front of one unmarks those pixels.
            stencil: if matches!(style, RoomStyle::Bare | RoomStyle::Albedo) {
                crate::backend::StencilTest::Off
            } else {
                crate::backend::StencilTest::Unmark
            },
        },
        variants,
    )
}

/// Surface area of the scene's bounding box: the area the analytic room's
/// ambient term spreads a light's flux over.
pub fn room_area(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds();
    let size = hi - lo;
    2.0 * (size.x * size.y + size.y * size.z + size.z * size.x)
}

/// The light shared by every room draw: the first area light as a point
/// emitter at its centre, and an ambient term standing in for the indirect
/// light (radiance ≈ ρ/(1 − ρ) · light area / room area · L for ρ = ½).
fn room_lighting(scene: &Scene) -> RoomLight {
    let Some(light) = scene.lights.first() else {
        return RoomLight::default();
    };
    let room_area = room_area(scene);
    // Ambient radiance = L · area / room area; the block carries L · area.
    let ambient = if room_area > 0.0 {
        1.0 / room_area
    } else {
        0.0
    };
    RoomLight {
        position: light.center.extend(1.0),
        normal: light.normal().extend(ambient),
        radiance: (light.radiance * light.area()).extend(1.0),
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
