//! The engine's side of texture inference: `inference::probe::ProbeRenderer`
//! on Vulkan, with the playback pipelines and samplers and float (RGBA32F)
//! textures and targets, so the rendering matrix is exact for this device.

use crate::backend::upload::upload_image;
use crate::backend::{
    Binding, Buffer, Device, Filtering, GpuError, GpuResult, Image, ImageDesc, Pipeline, Sampler,
};
use crate::gpu_scene::GpuMesh;
use crate::graph::{Executor, Pass, Usage};
use crate::passes::mirror::{fresnel_lut_image, mirror_pipeline};
use crate::passes::probe::ProbePass;
use crate::passes::readback::ReadbackPass;
use crate::passes::room::{RoomStyle, room_pipeline};
use crate::passes::room_albedo::SurfaceAlbedo;
use crate::passes::target::{Load, Target};
use crate::shader_interface::{MirrorPush, RoomPush};
use ash::vk;
use glam::{Mat4, Vec4};
use gpu_allocator::MemoryLocation;
use inference::probe::{Lookup, ProbeError, ProbeGeometry, ProbeRenderer};
use inference::scene::Mesh;
use inference::solve::layout::TextureLayout;

const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const DEPTH: vk::Format = crate::renderer::DEPTH_FORMAT;

struct Targets {
    color: Image,
    depth: Image,
    readback: Buffer,
    width: u32,
    height: u32,
}

struct Uploaded {
    key: u64,
    mesh: GpuMesh,
    /// Cube lookups as the mirror pipeline's texgen stream.
    texgen: Option<Buffer>,
}

struct ProbeTexture {
    layout: TextureLayout,
    /// Read from the nearest MIP level only (the set's sampler).
    one_level: bool,
    image: Image,
    set: vk::DescriptorSet,
}

pub struct VulkanProbe {
    device: Device,
    executor: Executor,
    bare: Pipeline,
    /// The room passes' albedo alone (`RoomStyle::Albedo`); its set layout
    /// is the bare pipeline's, so it draws with the bare set.
    albedo: Pipeline,
    mirror: Pipeline,
    lut: Image,
    repeat: Sampler,
    /// The light maps' sampler: repeat, nearest MIP level.
    repeat_one_level: Sampler,
    clamp: Sampler,
    targets: Option<Targets>,
    uploaded: Option<Uploaded>,
    texture: Option<ProbeTexture>,
    /// The mirror pipeline's set and the bare one's, once allocated.
    sets: [Option<vk::DescriptorSet>; 2],
    /// Probe renders made so far.
    pub renders: u32,
}

impl VulkanProbe {
    pub fn new(device: &Device) -> GpuResult<Self> {
        let mut executor = Executor::new(device)?;
        let lut = fresnel_lut_image(device, &mut executor)?;
        Ok(Self {
            device: device.clone(),
            bare: room_pipeline(device, RoomStyle::Bare, FORMAT, DEPTH)?,
            albedo: room_pipeline(device, RoomStyle::Albedo, FORMAT, DEPTH)?,
            mirror: mirror_pipeline(device, FORMAT, DEPTH)?,
            lut,
            executor,
            // The playback samplers: repeat for 2D textures, clamp for cubes.
            repeat: Sampler::trilinear(device, vk::SamplerAddressMode::REPEAT)?,
            repeat_one_level: Sampler::new(
                device,
                vk::SamplerAddressMode::REPEAT,
                Filtering::MipNearest,
            )?,
            clamp: Sampler::trilinear(device, vk::SamplerAddressMode::CLAMP_TO_EDGE)?,
            targets: None,
            uploaded: None,
            texture: None,
            sets: [None; 2],
            renders: 0,
        })
    }

    fn ensure_targets(&mut self, width: u32, height: u32) -> GpuResult<()> {
        if self
            .targets
            .as_ref()
            .is_some_and(|t| (t.width, t.height) == (width, height))
        {
            return Ok(());
        }
        if let Some(old) = self.targets.take() {
            self.executor.states.forget(&old.color);
            self.executor.states.forget(&old.depth);
        }
        let color = Image::new(
            &self.device,
            "probe colour",
            ImageDesc::new_2d(FORMAT, width, height)
                .usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC),
        )?;
        let depth = Image::new(
            &self.device,
            "probe depth",
            ImageDesc::new_2d(DEPTH, width, height)
                .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        let readback = Buffer::new(
            &self.device,
            "probe read-back",
            u64::from(width) * u64::from(height) * 16,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        self.targets = Some(Targets {
            color,
            depth,
            readback,
            width,
            height,
        });
        Ok(())
    }

    fn ensure_mesh(&mut self, geometry: &ProbeGeometry) -> GpuResult<()> {
        if self
            .uploaded
            .as_ref()
            .is_some_and(|u| u.key == geometry.key)
        {
            return Ok(());
        }
        let n = geometry.positions.len();
        let uvs = match geometry.lookup.uvs() {
            Some(uvs) => uvs.to_vec(),
            None => vec![glam::Vec2::ZERO; n],
        };
        let mesh = Mesh {
            positions: geometry.positions.clone(),
            normals: vec![glam::Vec3::Y; n],
            uvs,
            indices: geometry.indices.clone(),
        };
        let texgen = match &geometry.lookup {
            // cos θ = 1 reads LUT 0, so Schlick with F0 = 1 is exactly 1.
            Lookup::Cube { dirs, .. } => {
                let data: Vec<[f32; 4]> = dirs.iter().map(|d| [d.x, d.y, d.z, 1.0]).collect();
                Some(Buffer::with_data(
                    &self.device,
                    "probe texgen",
                    vk::BufferUsageFlags::VERTEX_BUFFER,
                    &data,
                )?)
            }
            Lookup::Uv(_) | Lookup::UvNearestLevel(_) => None,
        };
        self.uploaded = Some(Uploaded {
            key: geometry.key,
            mesh: GpuMesh::upload(&self.device, "probe mesh", &mesh)?,
            texgen,
        });
        Ok(())
    }

    fn upload_texture(
        &mut self,
        layout: &TextureLayout,
        lookup: &Lookup,
        texels: &[[f32; 4]],
    ) -> GpuResult<()> {
        let cube = matches!(lookup, Lookup::Cube { .. });
        let one_level = matches!(lookup, Lookup::UvNearestLevel(_));
        if self
            .texture
            .as_ref()
            .is_none_or(|t| t.layout != *layout || t.one_level != one_level)
        {
            if let Some(old) = self.texture.take() {
                self.executor.states.forget(&old.image);
            }
            let (w, h) = layout.level_size(0);
            let base = if cube {
                ImageDesc::new_cube(FORMAT, w)
            } else {
                ImageDesc::new_2d(FORMAT, w, h)
            };
            let desc = ImageDesc {
                mip_levels: layout.levels(),
                ..base
            }
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
            let image = Image::new(&self.device, "probe texture", desc)?;
            // One set per pipeline, rewritten for each new texture: a
            // compile changes layouts hundreds of times, more than a pool
            // holds.
            let (pipeline, slot, bindings) = if cube {
                let b = vec![
                    Binding::Image(image.view, self.clamp.raw),
                    Binding::Image(self.lut.view, self.clamp.raw),
                ];
                (&self.mirror, &mut self.sets[0], b)
            } else {
                let sampler = if one_level {
                    &self.repeat_one_level
                } else {
                    &self.repeat
                };
                let b = vec![Binding::Image(image.view, sampler.raw)];
                (&self.bare, &mut self.sets[1], b)
            };
            let set = match *slot {
                // SAFETY: every probe render was waited for; the set is idle.
                Some(set) => unsafe {
                    pipeline.rewrite_set(set, &bindings);
                    set
                },
                None => *slot.insert(pipeline.descriptor_set(&bindings)?),
            };
            self.texture = Some(ProbeTexture {
                layout: layout.clone(),
                one_level,
                image,
                set,
            });
        }
        let Some(texture) = &self.texture else {
            return Err(GpuError::Invalid("probe texture missing".into()));
        };
        // Layout order (level-major, then face, then rows) is the upload order.
        upload_image(
            &self.device,
            self.executor.commands(),
            &texture.image,
            bytemuck::cast_slice(texels),
        )?;
        self.executor.states.assume(&texture.image, Usage::Sampled);
        Ok(())
    }

    /// A diffuse surface's albedo at `geometry`'s view exactly as the room
    /// passes draw it (`surface`: a pattern in closed form, or `texels`
    /// read through the room's sampler): the light-map solve's factor.
    pub fn render_albedo(
        &mut self,
        geometry: &ProbeGeometry,
        layout: &TextureLayout,
        texels: &[[f32; 4]],
        surface: SurfaceAlbedo,
    ) -> GpuResult<Vec<[f32; 4]>> {
        if !matches!(geometry.lookup, Lookup::Uv(_)) {
            return Err(GpuError::Invalid(
                "an albedo probe reads uv lookups (the room's sampler)".into(),
            ));
        }
        self.render_with(geometry, layout, texels, Some(surface))
    }

    fn render_gpu(
        &mut self,
        geometry: &ProbeGeometry,
        layout: &TextureLayout,
        texels: &[[f32; 4]],
    ) -> GpuResult<Vec<[f32; 4]>> {
        self.render_with(geometry, layout, texels, None)
    }

    /// One probe render: the mirror pipeline for cube lookups, else the
    /// albedo pipeline for `surface`, else the bare one.
    fn render_with(
        &mut self,
        geometry: &ProbeGeometry,
        layout: &TextureLayout,
        texels: &[[f32; 4]],
        surface: Option<SurfaceAlbedo>,
    ) -> GpuResult<Vec<[f32; 4]>> {
        let cube = probe_is_cube(geometry, layout, texels)?;
        self.ensure_targets(geometry.width, geometry.height)?;
        self.ensure_mesh(geometry)?;
        self.upload_texture(layout, &geometry.lookup, texels)?;
        let (Some(targets), Some(uploaded), Some(texture)) =
            (&self.targets, &self.uploaded, &self.texture)
        else {
            return Err(GpuError::Invalid("probe resources missing".into()));
        };
        let view_proj: Mat4 = geometry.view_proj;
        let lod_bias = match geometry.lookup {
            Lookup::Cube { lod_bias, .. } => lod_bias,
            Lookup::Uv(_) | Lookup::UvNearestLevel(_) => 0.0,
        };
        let surface_or_white = surface.unwrap_or(SurfaceAlbedo::of(glam::Vec3::ONE, None));
        let push_bare = move |p: &Pipeline, cmd| {
            p.bind_variant(
                cmd,
                surface_or_white.variant,
                Some(texture.set),
                &RoomPush {
                    view_proj,
                    albedo: surface_or_white.first,
                    emission: Vec4::ZERO,
                    pattern: surface_or_white.second,
                },
            )
        };
        let push_mirror = move |p: &Pipeline, cmd| {
            p.bind(
                cmd,
                Some(texture.set),
                &MirrorPush {
                    view_proj,
                    f0: glam::Vec3::ONE.extend(lod_bias),
                },
            )
        };
        let target = Target {
            color: &targets.color,
            depth: &targets.depth,
            level: 0,
            layer: 0,
            load: Load::Clear,
            front_face: vk::FrontFace::COUNTER_CLOCKWISE,
            area: None,
        };
        let probe = ProbePass {
            device: &self.device,
            pipeline: match (cube, surface) {
                (true, _) => &self.mirror,
                (false, Some(_)) => &self.albedo,
                (false, None) => &self.bare,
            },
            set: texture.set,
            push: if cube { &push_mirror } else { &push_bare },
            mesh: &uploaded.mesh,
            per_vertex: uploaded.texgen.as_ref(),
            target,
            sampled: if cube {
                vec![&texture.image, &self.lut]
            } else {
                vec![&texture.image]
            },
        };
        let readback = ReadbackPass {
            device: &self.device,
            image: &targets.color,
            buffer: &targets.readback,
        };
        let passes: [&dyn Pass; 2] = [&probe, &readback];
        self.executor.run(&passes)?;
        self.renders += 1;
        let texel_count = (targets.width * targets.height) as usize;
        let bytes = targets.readback.mapped()?;
        Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes[..texel_count * 16]).to_vec())
    }
}

/// Whether a probe render reads a cube map (else a 2D texture), after
/// checking that `texels` fill `layout` and the lookups match its kind.
fn probe_is_cube(
    geometry: &ProbeGeometry,
    layout: &TextureLayout,
    texels: &[[f32; 4]],
) -> GpuResult<bool> {
    if texels.len() != layout.len() {
        return Err(GpuError::Invalid(format!(
            "probe texture: {} texels for a layout of {}",
            texels.len(),
            layout.len()
        )));
    }
    let cube = matches!(geometry.lookup, Lookup::Cube { .. });
    if cube != (layout.faces() == 6) {
        return Err(GpuError::Invalid(
            "cube lookups need a cube layout and uv lookups a 2D one".into(),
        ));
    }
    Ok(cube)
}

impl ProbeRenderer for VulkanProbe {
    fn render(
        &mut self,
        geometry: &ProbeGeometry,
        layout: &TextureLayout,
        texels: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError> {
        self.render_gpu(geometry, layout, texels)
            .map_err(|e| ProbeError::Render(e.to_string()))
    }
}
