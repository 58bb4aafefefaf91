//! Owns everything a scene needs on the device and builds each frame as an
//! explicit list of passes — only the passes the scene requires.

use crate::backend::{Buffer, Device, GpuError, GpuResult, Image, ImageDesc};
use crate::compile::room::RoomMaps;
use crate::gpu_scene::GpuScene;
use crate::graph::{Executor, Pass, PassTiming};
use crate::passes::em_capture::{CubeTarget, EmCapturePass, MipPass};
use crate::passes::mirror::{MirrorDraw, MirrorRenderer};
use crate::passes::pem_deferred::GBuffer;
use crate::passes::readback::ReadbackPass;
use crate::passes::room::{RoomRenderer, RoomStyle};
use crate::passes::room_maps::upload_room_maps;
use crate::passes::target::{Target, area_of};
use crate::pem::player::{PemPlayer, PemSettings};
use crate::pem::samples::SampleBlend;
use crate::pem::source::MapSource;
use ash::vk;
use glam::{Mat4, Vec3};
use half::f16;
use inference::scene::{Material, Scene};
use std::time::Instant;

pub const COLOR_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// Depth and stencil: the reflectors' G-buffer pass marks their pixels in
/// the stencil, so the compositing pass shades only those.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT_S8_UINT;
/// EM resolution when an object's `[em]` settings give none.
pub const DEFAULT_EM_RESOLUTION: u32 = 256;

/// What a frame draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameMode {
    /// The lit room, reflectors from one static cube map each.
    StaticEm,
    /// Every mesh with one texture: the reference cost of drawing at all.
    Bare,
    /// The lit room, reflectors from parameterized maps (see `set_pem`).
    Pem,
    /// The lit room, glass by hybrid rendering (`crate::glass`).
    Hybrid,
}

/// A reflective object and the static environment map it samples.
struct Reflector {
    draw: MirrorDraw,
    cube: CubeTarget,
    /// World-space vertices, the input of CPU texgen every frame.
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// World-space bounds, for the mirror pass's render area.
    bounds: (Vec3, Vec3),
}

/// Why a frame could not be drawn: the device (kept typed: device lost,
/// out of memory, …) or the maps it needed (reading or decoding them; the
/// codec's error stays inside, for `downcast_ref`).
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Maps(#[from] anyhow::Error),
}

/// CPU-side costs of one frame, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuTimes {
    pub texgen_ms: f64,
    pub upload_ms: f64,
    pub submit_ms: f64,
    /// Reading maps into staging (codec decode or EXR read).
    pub decode_ms: f64,
    pub decoded_maps: u32,
    /// Of those, maps decoded ahead on the worker thread.
    pub prefetched_maps: u32,
}

pub struct FrameStats {
    pub passes: Vec<PassTiming>,
    pub cpu: CpuTimes,
}

pub struct Renderer {
    device: Device,
    executor: Executor,
    gpu: GpuScene,
    room: RoomRenderer,
    bare: RoomRenderer,
    mirror: MirrorRenderer,
    reflectors: Vec<Reflector>,
    color: Image,
    depth: Image,
    readback: Buffer,
    width: u32,
    height: u32,
    projection: Mat4,
    texgen_scratch: Vec<inference::texgen::TexgenVertex>,
    pem: Option<PemPlayer>,
    /// Per-pixel lookups of deferred PEM compositing (frame-sized).
    gbuffer: GBuffer,
    /// The scene's glass object (drawn in static-EM and hybrid frames).
    pub glass: Option<crate::glass::GlassPlayer>,
    /// The last frame's view-projection (where its G-buffer was written).
    last_view_proj: Mat4,
    /// What set-up cost on the GPU (static EM capture, MIP chain).
    pub setup_timings: Vec<PassTiming>,
}

impl Renderer {
    pub fn new(device: &Device, scene: &Scene, width: u32, height: u32) -> GpuResult<Self> {
        if width == 0 || height == 0 {
            return Err(GpuError::Invalid(format!("frame size {width}x{height}")));
        }
        let mut executor = Executor::new(device)?;
        let gpu = GpuScene::upload(device, &mut executor, scene)?;
        let room = RoomRenderer::new(
            device,
            scene,
            &gpu,
            RoomStyle::Lit,
            COLOR_FORMAT,
            DEPTH_FORMAT,
        )?;
        let bare = RoomRenderer::new(
            device,
            scene,
            &gpu,
            RoomStyle::Bare,
            COLOR_FORMAT,
            DEPTH_FORMAT,
        )?;
        let mirror = MirrorRenderer::new(device, &mut executor, COLOR_FORMAT, DEPTH_FORMAT)?;
        let mut reflectors = Vec::new();
        for (index, object) in scene.objects.iter().enumerate() {
            let f0 = match scene.materials.get(object.material) {
                Some(Material::Mirror { f0 }) | Some(Material::Glossy { f0, .. }) => *f0,
                _ => continue,
            };
            let size = object
                .em
                .as_ref()
                .map_or(DEFAULT_EM_RESOLUTION, |em| em.resolution);
            let cube = CubeTarget::new(
                device,
                &format!("{} static EM", object.name),
                size,
                COLOR_FORMAT,
                object.mesh.area_weighted_centroid(),
            )?;
            let draw = mirror.draw_for(index, object.mesh.positions.len(), f0, &cube.color)?;
            reflectors.push(Reflector {
                draw,
                cube,
                positions: object.mesh.positions.clone(),
                normals: object.mesh.normals.clone(),
                bounds: object.mesh.bounds(),
            });
        }
        let color = Image::new(
            device,
            "frame colour",
            ImageDesc::new_2d(COLOR_FORMAT, width, height)
                .usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC),
        )?;
        let depth = Image::new(
            device,
            "frame depth",
            ImageDesc::new_2d(DEPTH_FORMAT, width, height)
                .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        let readback = Buffer::new(
            device,
            "frame read-back",
            u64::from(width) * u64::from(height) * 8,
            vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuToCpu,
        )?;
        let glass =
            crate::glass::GlassPlayer::for_scene(device, scene, (COLOR_FORMAT, DEPTH_FORMAT))?;
        // Shared with the tracer so traced and rasterised pixels line up exactly.
        let far = inference::trace::camera::far_plane(scene);
        let projection = inference::trace::camera::projection(scene, width, height);
        let mut renderer = Self {
            device: device.clone(),
            executor,
            gpu,
            room,
            bare,
            mirror,
            reflectors,
            color,
            depth,
            readback,
            width,
            height,
            projection,
            texgen_scratch: Vec::new(),
            pem: None,
            gbuffer: GBuffer::new(device, width, height)?,
            glass,
            last_view_proj: Mat4::IDENTITY,
            setup_timings: Vec::new(),
        };
        renderer.setup_timings = renderer.capture_static_ems(scene.camera.near, far)?;
        Ok(renderer)
    }

    /// Lights the room from `maps` (inferred light maps) from the next
    /// frame on, or analytically when None.
    pub fn set_room(&mut self, scene: &Scene, maps: Option<&RoomMaps>) -> GpuResult<()> {
        self.room = match maps {
            Some(maps) => {
                let uploaded = upload_room_maps(&self.device, &mut self.executor, maps)?;
                let (c, d) = (COLOR_FORMAT, DEPTH_FORMAT);
                RoomRenderer::inferred(&self.device, scene, &self.gpu, uploaded, c, d)?
            }
            None => RoomRenderer::new(
                &self.device,
                scene,
                &self.gpu,
                RoomStyle::Lit,
                COLOR_FORMAT,
                DEPTH_FORMAT,
            )?,
        };
        Ok(())
    }

    /// Sets up PEM playback (`FrameMode::Pem`) with `settings`, reading
    /// maps from `source`; replaces any earlier PEM set-up.
    pub fn set_pem(
        &mut self,
        scene: &Scene,
        settings: PemSettings,
        source: MapSource,
    ) -> anyhow::Result<()> {
        if let Some(old) = self.pem.take() {
            old.release(&mut self.executor);
        }
        self.pem = Some(PemPlayer::new(
            &self.device,
            &mut self.executor,
            scene,
            settings,
            source,
            &self.gbuffer,
            (COLOR_FORMAT, DEPTH_FORMAT),
        )?);
        Ok(())
    }

    /// Lets background map decoding finish before frames are timed.
    pub fn settle(&mut self) {
        if let Some(p) = self.pem.as_mut() {
            p.settle();
        }
    }

    /// The samples a PEM frame from `eye` draws (None without PEM set-up).
    pub fn pem_blend(&self, eye: Vec3) -> Option<SampleBlend> {
        Some(self.pem.as_ref()?.blend(eye))
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Renders every reflector's static EM (set-up, once): the room into
    /// six faces, then each MIP level from the one above.
    fn capture_static_ems(&mut self, near: f32, far: f32) -> GpuResult<Vec<PassTiming>> {
        let mut passes: Vec<Box<dyn Pass + '_>> = Vec::new();
        let glass = self.glass.as_ref().map(|g| &g.cube);
        for cube in self.reflectors.iter().map(|r| &r.cube).chain(glass) {
            passes.push(Box::new(EmCapturePass {
                room: &self.room,
                gpu: &self.gpu,
                cube,
                near,
                far,
            }));
            for level in 1..cube.color.desc.mip_levels {
                passes.push(Box::new(MipPass {
                    device: &self.device,
                    image: &cube.color,
                    level,
                    name: format!("em_mip{level}"),
                }));
            }
        }
        let list: Vec<&dyn Pass> = passes.iter().map(|p| p.as_ref()).collect();
        self.executor.run(&list)
    }

    /// Renders one frame from `eye` (looking at `center`) and reads it back.
    pub fn frame(
        &mut self,
        mode: FrameMode,
        eye: Vec3,
        view: Mat4,
    ) -> Result<FrameStats, RenderError> {
        let view_proj = self.projection * view;
        self.last_view_proj = view_proj;
        let mut cpu = CpuTimes::default();
        if matches!(mode, FrameMode::StaticEm | FrameMode::Hybrid) {
            self.texgen(eye, &mut cpu)?;
        }
        let size = (self.width, self.height);
        crate::glass::prepare_frame(self.glass.as_mut(), mode, (eye, view_proj), size, &mut cpu)?;
        let target = Target {
            color: &self.color,
            depth: &self.depth,
            level: 0,
            layer: 0,
            clear: true,
            front_face: vk::FrontFace::COUNTER_CLOCKWISE,
            area: None,
        };
        let mut blend = None;
        if mode == FrameMode::Pem {
            let Some(pem) = self.pem.as_mut() else {
                return Err(GpuError::Invalid("PEM frame without set_pem()".into()).into());
            };
            let b = pem.blend(eye);
            let prepared = pem.prepare(eye, &b)?;
            cpu.texgen_ms += prepared.texgen_ms;
            cpu.decode_ms += prepared.decode_ms;
            cpu.decoded_maps += prepared.decoded_maps;
            cpu.prefetched_maps += prepared.prefetched_maps;
            blend = Some(b);
        }
        let mut passes: Vec<Box<dyn Pass + '_>> = Vec::new();
        match mode {
            FrameMode::StaticEm | FrameMode::Pem | FrameMode::Hybrid => {
                let upload = match (&self.pem, mode) {
                    (Some(pem), FrameMode::Pem) => pem.upload_pass()?,
                    _ => None,
                };
                if let Some(upload) = upload {
                    passes.push(Box::new(upload));
                }
                passes.push(Box::new(
                    self.room.pass("room", &self.gpu, target, view_proj),
                ));
                let later = Target {
                    clear: false,
                    ..target
                };
                if let (Some(pem), Some(b)) = (&self.pem, &blend) {
                    passes.extend(pem.draw_passes(
                        &self.gpu,
                        &self.gbuffer,
                        b,
                        later,
                        view_proj,
                    )?);
                } else if !self.reflectors.is_empty() {
                    let area = area_of(
                        view_proj,
                        self.reflectors.iter().map(|r| r.bounds),
                        self.width,
                        self.height,
                    );
                    let later = Target { area, ..later };
                    passes.push(Box::new(self.mirror.pass(
                        &self.gpu,
                        self.reflectors.iter().map(|r| &r.draw).collect(),
                        self.reflectors.iter().map(|r| &r.cube.color).collect(),
                        later,
                        view_proj,
                    )));
                }
                if let Some(g) = self.glass.as_ref().filter(|_| mode != FrameMode::Pem) {
                    let area = area_of(view_proj, [g.bounds()], self.width, self.height);
                    passes.push(Box::new(g.pass(Target { area, ..later }, view_proj)));
                }
            }
            FrameMode::Bare => {
                passes.push(Box::new(
                    self.bare.pass("bare", &self.gpu, target, view_proj),
                ));
            }
        }
        passes.push(Box::new(ReadbackPass {
            device: &self.device,
            image: &self.color,
            buffer: &self.readback,
        }));
        let list: Vec<&dyn Pass> = passes.iter().map(|p| p.as_ref()).collect();
        let start = Instant::now();
        let timings = self.executor.run(&list)?;
        cpu.submit_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(FrameStats {
            passes: timings,
            cpu,
        })
    }

    /// Replaces the glass object's shell map (all levels, f16 RGBA in
    /// upload order) — the traced room instead of the rasterised capture.
    pub fn load_glass_shell(&mut self, bytes: &[u8]) -> GpuResult<()> {
        let Some(g) = self.glass.as_ref() else {
            return Err(GpuError::Invalid("no glass object".into()));
        };
        let image = g.shell_map();
        crate::backend::upload::upload_image(&self.device, self.executor.commands(), image, bytes)?;
        self.executor
            .states
            .assume(image, crate::graph::Usage::Sampled);
        Ok(())
    }

    /// CPU texgen for every reflector, then the copy into its vertex buffer
    /// (host-visible; the previous frame's fence guarantees it is idle).
    fn texgen(&mut self, eye: Vec3, cpu: &mut CpuTimes) -> GpuResult<()> {
        for r in &mut self.reflectors {
            let start = Instant::now();
            let out = &mut self.texgen_scratch;
            out.resize(r.positions.len(), [0.0; 4]);
            inference::texgen::sphere_at_infinity(eye, &r.positions, &r.normals, out);
            let generated = Instant::now();
            let bytes: &[u8] = bytemuck::cast_slice(out);
            r.draw.texgen.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
            cpu.texgen_ms += (generated - start).as_secs_f64() * 1e3;
            cpu.upload_ms += generated.elapsed().as_secs_f64() * 1e3;
        }
        Ok(())
    }

    /// The static EM of the `index`-th reflector (scene order): its cube
    /// size, its world-space EM origin and every texel of every MIP level as
    /// linear RGBA f32, level-major, then face, then rows.
    pub fn static_em(&mut self, index: usize) -> GpuResult<(u32, Vec3, Vec<[f32; 4]>)> {
        let Some(r) = self.reflectors.get(index) else {
            return Err(GpuError::Invalid(format!("no reflector {index}")));
        };
        let bytes = crate::backend::upload::image_bytes(&r.cube.color)?;
        let buffer = Buffer::new(
            &self.device,
            "static EM read-back",
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuToCpu,
        )?;
        let pass = ReadbackPass {
            device: &self.device,
            image: &r.cube.color,
            buffer: &buffer,
        };
        self.executor.run(&[&pass])?;
        let texels = rgba16f_to_f32(&buffer.mapped()?[..bytes as usize]);
        Ok((r.cube.color.desc.width, r.cube.origin, texels))
    }

    /// Reflector pixels the last deferred PEM frame covered (counted on the
    /// G-buffer read back: the cosine's clear value marks the rest).
    pub fn covered_pixels(&mut self) -> GpuResult<u64> {
        let image = &self.gbuffer.images[2];
        let bytes = crate::backend::upload::image_bytes(image)?;
        let buffer = Buffer::new(
            &self.device,
            "g-buffer read-back",
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuToCpu,
        )?;
        let pass = ReadbackPass {
            device: &self.device,
            image,
            buffer: &buffer,
        };
        self.executor.run(&[&pass])?;
        let cos: &[f32] = bytemuck::cast_slice(&buffer.mapped()?[..bytes as usize]);
        // Only the last G-buffer pass's area was cleared this frame.
        let bounds = self.reflectors.iter().map(|r| r.bounds);
        let full = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: self.width,
                height: self.height,
            },
        };
        let a = area_of(self.last_view_proj, bounds, self.width, self.height).unwrap_or(full);
        let (x0, y0) = (a.offset.x.max(0) as usize, a.offset.y.max(0) as usize);
        let (x1, y1) = (x0 + a.extent.width as usize, y0 + a.extent.height as usize);
        let w = self.width as usize;
        Ok((y0..y1.min(self.height as usize))
            .flat_map(|y| (x0..x1.min(w)).map(move |x| y * w + x))
            .filter(|&i| cos[i] >= -1.5)
            .count() as u64)
    }

    /// The last frame's pixels as linear RGBA f32, row-major from the top.
    pub fn pixels(&self) -> GpuResult<Vec<[f32; 4]>> {
        let bytes = self.readback.mapped()?;
        let texels = (self.width * self.height) as usize;
        Ok(rgba16f_to_f32(&bytes[..texels * 8]))
    }
}

/// RGBA16F texels read back from the device as linear RGBA f32.
fn rgba16f_to_f32(bytes: &[u8]) -> Vec<[f32; 4]> {
    bytemuck::cast_slice::<u8, f16>(bytes)
        .chunks_exact(4)
        .map(|c| [c[0].to_f32(), c[1].to_f32(), c[2].to_f32(), c[3].to_f32()])
        .collect()
}
