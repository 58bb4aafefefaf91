//! Owns everything a scene needs on the device and builds each frame as an
//! explicit list of passes — only the passes the scene requires.

mod frame_passes;
mod glass;
mod light_path;
mod readback;
mod reflectors;

use crate::backend::{Buffer, Device, GpuError, GpuResult, Image, ImageDesc};
use crate::compile::room::RoomMaps;
use crate::gpu_scene::GpuScene;
use crate::graph::{Executor, Pass, PassTiming};
use crate::passes::em_capture::{EmCapturePass, MipPass};
use crate::passes::mirror::MirrorRenderer;
use crate::passes::pem_deferred::GBuffer;
use crate::passes::room::{RoomRenderer, RoomStyle};
use crate::passes::room_maps::upload_room_maps;
use crate::pem::ahead::{TexgenFrame, TexgenInputs, TexgenRequest};
use crate::pem::player::{PemPlayer, PemSettings};
use crate::pem::samples::SampleBlend;
use crate::pem::source::MapSource;
use ash::vk;
use frame_passes::{FrameParts, frame_passes};
use glam::{Mat4, Vec3};
use inference::scene::Scene;
pub use readback::half_pixels;
use reflectors::{Reflector, static_em_reflectors};
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
    /// The lit room, the reflector by reflection-space IBR (see `set_rem`).
    Rem,
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
    /// Waiting for the worker to finish a map it was still decoding.
    pub prefetch_wait_ms: f64,
    /// PEM reflectors whose texgen was computed during the previous frame.
    pub texgen_ahead: u32,
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
    rem: Option<crate::rem::RemPlayer>,
    /// `--light-path`: the relit panorama behind the static EMs.
    light_path: Option<light_path::LightPathGpu>,
    /// Per-pixel lookups of deferred PEM compositing (frame-sized).
    gbuffer: GBuffer,
    /// The scene's glass object (drawn in static-EM and hybrid frames).
    pub glass: Option<crate::glass::GlassPlayer>,
    /// The next frame's eye and view, when the caller knows it: its CPU
    /// work (glass paths) starts while this frame renders.
    next_view: Option<(Vec3, Mat4)>,
    /// What set-up cost on the GPU (static EM capture, MIP chain).
    pub setup_timings: Vec<PassTiming>,
    /// Bytes of the maps the last `set_pem` (container), `set_rem` (source
    /// maps on the device) or glass per-sample shells (their container, or
    /// raw) set up, for the eval table.
    pub map_bytes: Option<u64>,
    /// Minutes the last `set_pem`'s container took to compile, as its key
    /// record keeps them (None when unknown or reading EXR maps).
    pub map_compile_minutes: Option<f64>,
}

impl Renderer {
    pub fn new(device: &Device, scene: &Scene, width: u32, height: u32) -> GpuResult<Self> {
        if width == 0 || height == 0 {
            return Err(GpuError::Invalid(format!("frame size {width}x{height}")));
        }
        let mut executor = Executor::new(device)?;
        let gpu = GpuScene::upload(device, &mut executor, scene)?;
        let room = room_renderer(device, scene, &gpu, RoomStyle::Lit)?;
        let bare = room_renderer(device, scene, &gpu, RoomStyle::Bare)?;
        let mirror = MirrorRenderer::new(device, &mut executor, COLOR_FORMAT, DEPTH_FORMAT)?;
        let reflectors = static_em_reflectors(device, scene, &mirror)?;
        let (color, depth, readback) = frame_images(device, width, height)?;
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
            rem: None,
            light_path: None,
            gbuffer: GBuffer::new(device, width, height)?,
            glass,
            next_view: None,
            setup_timings: Vec::new(),
            map_bytes: None,
            map_compile_minutes: None,
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
            None => room_renderer(&self.device, scene, &self.gpu, RoomStyle::Lit)?,
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
        self.map_bytes = source.container_bytes();
        self.map_compile_minutes = source.compile_seconds().map(|s| s / 60.0);
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

    /// Sets up reflection-space IBR (`FrameMode::Rem`) from `maps`;
    /// `blend` false draws the nearest source map alone.
    pub fn set_rem(
        &mut self,
        scene: &Scene,
        maps: &crate::rem::sources::SourceMaps,
        blend: bool,
    ) -> GpuResult<()> {
        let rem = crate::rem::RemPlayer::new(
            &self.device,
            &mut self.executor,
            scene,
            maps,
            blend,
            (COLOR_FORMAT, DEPTH_FORMAT),
        )?;
        self.map_bytes = Some(rem.bytes);
        self.map_compile_minutes = None;
        self.rem = Some(rem);
        Ok(())
    }

    /// The REM set-up's views and source bytes (None without `set_rem`).
    pub fn rem(&self) -> Option<&crate::rem::RemPlayer> {
        self.rem.as_ref()
    }

    /// Lets background map decoding finish before frames are timed.
    pub fn settle(&mut self) {
        if let Some(p) = self.pem.as_mut() {
            p.settle();
        }
    }

    /// Each map decoded ahead since the last call (PEM playback): its wall
    /// time on the worker while frames rendered.
    pub fn drain_ahead_decode_ms(&mut self) -> Vec<f64> {
        self.pem
            .as_mut()
            .map_or_else(Vec::new, |p| p.drain_ahead_decode_ms())
    }

    /// Waits for the glass's paths traced for an announced next view and
    /// drops them (that view will not be drawn next): `engine bench` ends
    /// each row's run with it, so no worker runs into another row.
    pub fn drop_glass_ahead(&mut self) {
        if let Some(g) = self.glass.as_mut() {
            g.drop_ahead();
        }
    }

    /// The samples a PEM frame from `eye` draws (None without PEM set-up).
    pub fn pem_blend(&self, eye: Vec3) -> Option<SampleBlend> {
        Some(self.pem.as_ref()?.blend(eye))
    }

    /// Blends PEM frames between these azimuth lines of the scene's grid
    /// only (`None`: all); no-op without PEM set-up. `engine place` uses
    /// it to measure a sparse placement on a dense compile.
    pub fn use_azimuth_lines(&mut self, lines: Option<&[u32]>) {
        if let Some(p) = self.pem.as_mut() {
            p.use_azimuth_lines(lines);
        }
    }

    /// The same for elevation rings (`engine place --rings`).
    pub fn use_rings(&mut self, rings: Option<&[u32]>) {
        if let Some(p) = self.pem.as_mut() {
            p.use_rings(rings);
        }
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

    /// Tells the renderer where the next frame looks from (playback knows its
    /// path), so that frame's CPU work can run while this one renders.
    pub fn set_next_view(&mut self, eye: Vec3, view: Mat4) {
        self.next_view = Some((eye, view));
    }

    /// Renders one frame from `eye` (looking at `center`) and reads it back.
    pub fn frame(
        &mut self,
        mode: FrameMode,
        eye: Vec3,
        view: Mat4,
    ) -> Result<FrameStats, RenderError> {
        let view_proj = self.projection * view;
        let mut cpu = CpuTimes::default();
        if matches!(mode, FrameMode::StaticEm | FrameMode::Hybrid) {
            self.texgen(eye, &mut cpu)?;
        }
        let size = (self.width, self.height);
        let next = self
            .next_view
            .take()
            .map(|(eye, view)| (eye, self.projection * view));
        let glass = self.glass.as_mut();
        crate::glass::prepare_frame(glass, mode, (eye, view_proj), next, size, &mut cpu)?;
        let blend = match mode {
            FrameMode::Pem => {
                let next_eye = next.map(|(eye, _)| eye);
                Some(self.prepare_pem((eye, next_eye), view_proj, &mut cpu)?)
            }
            _ => None,
        };
        let parts = FrameParts {
            device: &self.device,
            gpu: &self.gpu,
            room: &self.room,
            bare: &self.bare,
            mirror: &self.mirror,
            reflectors: &self.reflectors,
            pem: self.pem.as_ref(),
            rem: self.rem.as_ref().filter(|_| mode == FrameMode::Rem),
            light_path: self
                .light_path
                .as_ref()
                .filter(|_| mode == FrameMode::StaticEm),
            eye,
            gbuffer: &self.gbuffer,
            glass: self.glass.as_ref(),
            color: &self.color,
            depth: &self.depth,
            readback: &self.readback,
            width: self.width,
            height: self.height,
        };
        let passes = frame_passes(&parts, mode, blend.as_ref(), view_proj)?;
        let list: Vec<&dyn Pass> = passes.iter().map(|p| p.as_ref()).collect();
        // Frames in flight: the next PEM frame's texgen and bands on a
        // worker while the device renders this one (`pem::ahead`).
        let jobs = match (self.pem.as_ref(), next) {
            (Some(pem), Some((eye, view_proj))) if mode == FrameMode::Pem => {
                pem.ahead_jobs(eye, (view_proj, size))
            }
            _ => Vec::new(),
        };
        let start = Instant::now();
        let (timings, ahead) = run_beside(&mut self.executor, &list, jobs);
        let timings = timings?;
        cpu.submit_ms = start.elapsed().as_secs_f64() * 1e3;
        drop(list);
        drop(passes);
        if let (Some(pem), Some(ahead)) = (self.pem.as_mut(), ahead) {
            pem.set_ahead(ahead);
        }
        Ok(FrameStats {
            passes: timings,
            cpu,
        })
    }

    /// The samples a PEM frame from `eye` blends, their maps read into
    /// staging (and the next frame's, from `next_eye` when known, decoded
    /// ahead); what that cost on the CPU is added to `cpu`.
    fn prepare_pem(
        &mut self,
        (eye, next_eye): (Vec3, Option<Vec3>),
        view_proj: Mat4,
        cpu: &mut CpuTimes,
    ) -> Result<SampleBlend, RenderError> {
        let Some(pem) = self.pem.as_mut() else {
            return Err(GpuError::Invalid("PEM frame without set_pem()".into()).into());
        };
        let blend = pem.blend(eye);
        let prepared = pem.prepare(
            eye,
            (view_proj, (self.width, self.height)),
            &blend,
            next_eye,
        )?;
        cpu.texgen_ms += prepared.texgen_ms;
        cpu.decode_ms += prepared.decode_ms;
        cpu.decoded_maps += prepared.decoded_maps;
        cpu.prefetched_maps += prepared.prefetched_maps;
        cpu.prefetch_wait_ms += prepared.prefetch_wait_ms;
        cpu.texgen_ahead += prepared.texgen_ahead;
        Ok(blend)
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
}

/// Runs a frame's passes (waiting for the device) while a worker computes
/// the next frame's texgen `jobs`; what the worker made, if anything.
fn run_beside(
    executor: &mut Executor,
    list: &[&dyn Pass],
    jobs: Vec<(TexgenInputs<'_>, TexgenRequest)>,
) -> (GpuResult<Vec<PassTiming>>, Option<Vec<TexgenFrame>>) {
    std::thread::scope(|s| {
        let worker = (!jobs.is_empty()).then(|| {
            s.spawn(move || {
                jobs.iter()
                    .map(|(inputs, request)| inputs.compute(*request))
                    .collect::<Vec<_>>()
            })
        });
        let timings = executor.run(list);
        (timings, worker.and_then(|w| w.join().ok()))
    })
}

/// The room (lit or bare) drawn into the frame's formats.
fn room_renderer(
    device: &Device,
    scene: &Scene,
    gpu: &GpuScene,
    style: RoomStyle,
) -> GpuResult<RoomRenderer> {
    RoomRenderer::new(device, scene, gpu, style, COLOR_FORMAT, DEPTH_FORMAT)
}

/// The frame's colour and depth attachments and the host-visible buffer its
/// colour is read back into.
fn frame_images(device: &Device, width: u32, height: u32) -> GpuResult<(Image, Image, Buffer)> {
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
    Ok((color, depth, readback))
}
