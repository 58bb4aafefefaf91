//! Glass objects (Hakura's thesis ch. 6) on the device: the lens's shell
//! map and, every frame, its vertex ray paths traced on the CPU and drawn
//! by the glass pass.
//!
//! Hybrid frames tessellate the lens adaptively to τ subpixels and index
//! the room's box, whose map is the room traced from the lens centroid
//! (lookup = exit ray's hit on the box − centroid) or, where the scene
//! asks for them (`[objects.glass] shell_every`), the two nearest
//! per-sample maps inferred from traced frames ([`samples`]), blended;
//! where objects stand near the glass, layered shells ([`layers`]), each
//! exit ray reading every layer nearest first. The baseline (static
//! refraction EM) draws the lens's own mesh with one refraction at the
//! front surface, the traced map read at infinity.

pub mod ahead;
pub mod coverage;
pub mod layers;
pub mod samples;
pub mod shell;

use crate::backend::{Device, GpuError, GpuResult, Image};
use crate::passes::em_capture::CubeTarget;
use crate::passes::glass::{GlassGeometry, ShellSource};
use crate::passes::target::{AroundRoom, Target};
use ahead::{Ahead, PathRequest};
use ash::vk;
use glam::{Mat4, Vec3, Vec4};
use inference::glass::vertices::vertex_stream_padded;
use inference::glass::{Lens, MAX_SHELLS, ShellSet, ShellShape};
use inference::scene::Scene;
use std::sync::Arc;
use std::time::Instant;

/// How a frame draws the glass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlassKind {
    /// Adaptive tessellation, greedy two paths, the room shell.
    Hybrid,
    /// The static refraction EM baseline.
    StaticEm,
}

/// What the last frame's CPU side did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GlassFrameStats {
    pub vertices: usize,
    pub triangles: usize,
    /// Of those, the triangles that read every shell layer (layered
    /// frames; the rest read the outermost alone).
    pub layered_triangles: usize,
    /// Rays cast through the lens.
    pub rays: u64,
    /// Vertex ray paths (tessellation; with frames in flight, the wait
    /// for the worker) and stream building, ms.
    pub paths_ms: f64,
    pub stream_ms: f64,
}

/// One glass object's device state.
pub struct GlassPlayer {
    lens: Arc<Lens>,
    pub cube: CubeTarget,
    geometry: GlassGeometry,
    room: ShellSet,
    infinity: ShellSet,
    /// Tessellation threshold, subpixels.
    pub tau: f32,
    /// Per-sample maps composited deferred (G-buffer, then each lens pixel
    /// once) rather than in one forward pass (`--compositing multipass`);
    /// read when the maps are set ([`GlassPlayer::set_samples`]).
    pub deferred: bool,
    bounds: (Vec3, Vec3),
    /// The per-sample maps (a cube-map array) and their azimuths.
    samples: Option<(Image, Vec<f32>)>,
    /// This frame's blend of them (layers, weight), hybrid frames only.
    blend: Option<Vec4>,
    /// Layered shells: their maps (a cube-map array, nearest first) and
    /// the shells (the stream pads them to [`MAX_SHELLS`]).
    layers: Option<(Image, ShellSet)>,
    /// With per-sample layer maps (the array holds every sample's layers,
    /// sample after sample), their azimuths.
    layer_azimuths: Option<Vec<f32>>,
    /// This frame's push for the layered shaders: layers, the two blended
    /// samples' first array elements, the weight of the second.
    layer_blend: Vec4,
    /// The directions each inner layer covers ([`coverage`]).
    cones: Vec<coverage::Cone>,
    /// Whether this frame reads the layers (hybrid frames with layers),
    /// and how many of its indices lead with triangles that need them.
    layered_frame: Option<u32>,
    split: Vec<u32>,
    /// The deferred composite's scissor bands for this frame (empty: the
    /// lens's bounding rectangle) and their scratch.
    bands: Vec<vk::Rect2D>,
    band_pixels: Vec<glam::Vec2>,
    orbit: inference::scene::Orbit,
    stream: Vec<f32>,
    /// The next frame's paths, being traced (see [`GlassPlayer::prepare`]).
    ahead: Option<Ahead>,
    pub last: GlassFrameStats,
}

impl GlassPlayer {
    /// The first object with `[objects.glass]` settings, if any.
    pub fn for_scene(
        device: &Device,
        scene: &Scene,
        formats: (vk::Format, vk::Format),
    ) -> GpuResult<Option<GlassPlayer>> {
        let Some(object) = scene.objects.iter().find(|o| o.glass.is_some()) else {
            return Ok(None);
        };
        let settings = object.glass.clone().unwrap_or_default();
        let lens = Lens::new(scene, &object.name).map_err(|e| GpuError::Invalid(e.to_string()))?;
        let origin = object.mesh.area_weighted_centroid();
        let cube = CubeTarget::new(
            device,
            &format!("{} shell map", object.name),
            settings.resolution,
            formats.0,
            origin,
        )?;
        let geometry = GlassGeometry::new(device, &cube.color, formats)?;
        let shell = |shape| inference::glass::room_shell(scene, origin, shape);
        Ok(Some(GlassPlayer {
            room: shell(inference::glass::room_box_shape(scene)),
            infinity: shell(ShellShape::Infinity),
            bounds: object.mesh.bounds(),
            samples: None,
            blend: None,
            layers: None,
            layer_azimuths: None,
            layer_blend: Vec4::ZERO,
            cones: Vec::new(),
            layered_frame: None,
            split: Vec::new(),
            bands: Vec::new(),
            band_pixels: Vec::new(),
            orbit: scene.orbit.clone(),
            lens: Arc::new(lens),
            cube,
            geometry,
            tau: settings.tau,
            deferred: true,
            stream: Vec::new(),
            ahead: None,
            last: GlassFrameStats::default(),
        }))
    }

    /// The scene object index of the lens.
    pub fn lens_object(&self) -> u32 {
        self.lens.object
    }

    /// The lens (its mesh and BVH, built once with the player).
    pub fn lens(&self) -> Arc<Lens> {
        self.lens.clone()
    }

    /// The lens's world-space bounds (the pass's render area).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// What a `kind` frame from `eye` (`view_proj`, `size`) traces.
    pub fn request(
        &self,
        kind: GlassKind,
        (eye, view_proj): (Vec3, Mat4),
        size: (u32, u32),
    ) -> PathRequest {
        PathRequest {
            kind,
            eye,
            view_proj,
            size,
            tau: self.tau,
        }
    }

    /// The CPU side of a frame: vertex ray paths (taken from the worker when
    /// it traced this very view ahead), the stream, the upload; with `next`
    /// (the frame after this one), that frame's paths start on the worker,
    /// to run while the device renders this one. Returns (paths + stream
    /// ms, upload ms).
    pub fn prepare(
        &mut self,
        request: PathRequest,
        next: Option<PathRequest>,
    ) -> GpuResult<(f64, f64)> {
        let start = Instant::now();
        let tess = (self.ahead.take())
            .and_then(|a| a.take(&request))
            .unwrap_or_else(|| ahead::trace(&self.lens, &request));
        // The one worker was just taken: never two at once.
        self.ahead = next.and_then(|next| Ahead::start(self.lens.clone(), next));
        let layered = request.kind == GlassKind::Hybrid && self.layers.is_some();
        let shells = match (request.kind, &self.layers) {
            (GlassKind::Hybrid, Some((_, set))) => set,
            (GlassKind::Hybrid, None) => &self.room,
            (GlassKind::StaticEm, _) => &self.infinity,
        };
        self.blend = match (&self.samples, request.kind) {
            (Some((_, azimuths)), GlassKind::Hybrid) => {
                let az = self.orbit.angles(request.eye).0;
                samples::blend_of(azimuths, az)
                    .map(|(a, b, w)| Vec4::new(a as f32, b as f32, w, 0.0))
            }
            _ => None,
        };
        self.layer_blend = self.layer_push(request.eye);
        let traced = Instant::now();
        let slots = match layered {
            true => MAX_SHELLS,
            false => shells.shells.len(),
        };
        vertex_stream_padded(&tess, shells, slots, &mut self.stream);
        // Layered: the triangles an inner layer can reach first.
        let indices = match layered {
            true => {
                let n = coverage::split_triangles(
                    &self.stream,
                    &tess.indices,
                    &self.cones,
                    &mut self.split,
                );
                self.layered_frame = Some(n as u32);
                &self.split
            }
            false => {
                self.layered_frame = None;
                &tess.indices
            }
        };
        // Deferred per-sample frames composite band by band.
        self.bands = match (self.geometry.deferred(), self.blend, layered) {
            (true, Some(_), false) => crate::passes::bands::screen_bands(
                request.view_proj,
                &tess.positions,
                &tess.indices,
                request.size,
                &mut self.band_pixels,
            )
            .unwrap_or_default(),
            _ => Vec::new(),
        };
        let streamed = Instant::now();
        self.geometry.upload(&self.stream, indices)?;
        self.last = GlassFrameStats {
            vertices: tess.positions.len(),
            triangles: tess.indices.len() / 3,
            layered_triangles: self.layered_frame.map_or(0, |n| n as usize / 3),
            rays: tess.stats.rays,
            paths_ms: (traced - start).as_secs_f64() * 1e3,
            stream_ms: (streamed - traced).as_secs_f64() * 1e3,
        };
        Ok((
            (streamed - start).as_secs_f64() * 1e3,
            streamed.elapsed().as_secs_f64() * 1e3,
        ))
    }

    /// Waits for the next frame's paths, if any are being traced, and
    /// drops them: no worker outlives the frames that asked for it.
    pub fn drop_ahead(&mut self) {
        if let Some(ahead) = self.ahead.take() {
            ahead.finish();
        }
    }

    /// The passes drawing what [`GlassPlayer::prepare`] uploaded, around
    /// the room (see [`GlassGeometry::passes`]; `first`: nothing else lays
    /// the frame's depth before the room).
    pub fn passes<'a>(
        &'a self,
        target: Target<'a>,
        view_proj: Mat4,
        first: bool,
    ) -> AroundRoom<'a> {
        let source = match (&self.samples, self.blend, &self.layers, self.layered_frame) {
            (_, _, Some((image, _)), Some(first)) => {
                ShellSource::Layers(image, self.layer_blend, first)
            }
            (Some((image, _)), Some(blend), ..) => ShellSource::Samples(image, blend),
            _ => ShellSource::One(&self.cube.color),
        };
        (self.geometry).passes(source, target, view_proj, (&self.bands, first))
    }

    /// Plays hybrid frames from layered shells: `image` holds `set`'s maps
    /// (nearest first, uploaded and ready for sampling) — with `azimuths`,
    /// every per-sample map of each layer, sample after sample — and
    /// `cones` what each inner one covers (None: unknown, every direction).
    pub fn set_layers(
        &mut self,
        image: Image,
        (set, azimuths): (&ShellSet, Option<Vec<f32>>),
        cones: &[Option<coverage::Cone>],
    ) -> GpuResult<()> {
        let n = set.shells.len();
        if !(1..=MAX_SHELLS).contains(&n) {
            return Err(GpuError::Invalid(format!(
                "{n} shell layers: expected 1 to {MAX_SHELLS}"
            )));
        }
        let elements = n * azimuths.as_ref().map_or(1, |a| a.len().max(1));
        if image.desc.array as usize != elements {
            return Err(GpuError::Invalid(format!(
                "shell layers: {} array elements, expected {elements}",
                image.desc.array
            )));
        }
        self.geometry.set_layers(&image, azimuths.is_some())?;
        self.layers = Some((image, set.clone()));
        self.layer_azimuths = azimuths;
        // An inner layer that covers nothing never needs its triangles; it
        // keeps its place, so each cone is tested against its own shell.
        self.cones = (cones.iter().take(n - 1))
            .map(|c| c.unwrap_or(coverage::Cone::NONE))
            .collect();
        Ok(())
    }

    /// Has every lens triangle read every layer, as if each inner layer
    /// covered every direction: the reference the split is measured
    /// against (`examples/glass_layers.rs`).
    pub fn read_every_layer_everywhere(&mut self) {
        if self.layers.is_some() {
            self.cones = vec![coverage::Cone::ALL];
        }
    }

    /// The layered shaders' push for the eye at `eye`:
    /// (layers, first element of sample a, of sample b, weight of b);
    /// traced layers read elements 0 to n − 1.
    fn layer_push(&self, eye: Vec3) -> Vec4 {
        let Some((_, set)) = &self.layers else {
            return Vec4::ZERO;
        };
        let n = set.shells.len() as f32;
        let blend = (self.layer_azimuths.as_deref())
            .and_then(|azimuths| samples::blend_of(azimuths, self.orbit.angles(eye).0));
        match blend {
            Some((a, b, w)) => Vec4::new(n, a as f32 * n, b as f32 * n, w),
            None => Vec4::new(n, 0.0, 0.0, 0.0),
        }
    }

    /// How many per-sample maps of each shell layer hybrid frames blend
    /// (0: the traced layers, or no layers).
    pub fn layer_sample_count(&self) -> usize {
        self.layer_azimuths.as_ref().map_or(0, Vec::len)
    }

    /// How many shell layers hybrid frames read (1: the room's box alone).
    pub fn layer_count(&self) -> u32 {
        self.layers
            .as_ref()
            .map_or(1, |(_, set)| set.shells.len() as u32)
    }

    /// Plays hybrid frames of `size` from `image` (the per-sample maps at
    /// `azimuths`, uploaded and ready for sampling) instead of the one map.
    pub fn set_samples(
        &mut self,
        image: Image,
        azimuths: Vec<f32>,
        size: (u32, u32),
    ) -> GpuResult<()> {
        let deferred = self.deferred.then_some(size);
        self.geometry.set_samples(&image, deferred)?;
        self.samples = Some((image, azimuths));
        Ok(())
    }

    /// Back to the one map for every view (no per-sample maps, no layers).
    pub fn clear_samples(&mut self) {
        self.geometry.clear_samples();
        self.samples = None;
        self.blend = None;
        self.layers = None;
        self.layer_azimuths = None;
        self.cones.clear();
        self.layered_frame = None;
    }

    /// How many per-sample maps hybrid frames blend (0: the one map).
    pub fn sample_count(&self) -> usize {
        self.samples.as_ref().map_or(0, |s| s.1.len())
    }

    /// The shell map (the capture renders into it).
    pub fn shell_map(&self) -> &Image {
        &self.cube.color
    }
}

/// How a frame in `mode` draws the glass, if at all.
pub fn glass_kind(mode: crate::renderer::FrameMode) -> Option<GlassKind> {
    use crate::renderer::FrameMode;
    match mode {
        FrameMode::Hybrid => Some(GlassKind::Hybrid),
        FrameMode::StaticEm => Some(GlassKind::StaticEm),
        _ => None,
    }
}

/// The glass object's CPU side for a static-EM or hybrid frame from `eye`
/// (`view_proj`); other frames draw no glass. With `next` (the view of the
/// frame after this one), its paths start on a worker right away.
pub fn prepare_frame(
    glass: Option<&mut GlassPlayer>,
    mode: crate::renderer::FrameMode,
    view: (Vec3, Mat4),
    next: Option<(Vec3, Mat4)>,
    size: (u32, u32),
    cpu: &mut crate::renderer::CpuTimes,
) -> GpuResult<()> {
    let (Some(g), Some(kind)) = (glass, glass_kind(mode)) else {
        return Ok(());
    };
    let next = next.map(|next| g.request(kind, next, size));
    let (paths_ms, upload_ms) = g.prepare(g.request(kind, view, size), next)?;
    cpu.texgen_ms += paths_ms;
    cpu.upload_ms += upload_ms;
    Ok(())
}

/// Sets `renderer` up for hybrid frames with `tau` (the scene's when
/// None), per-sample maps composited `deferred` or forward, the room shell
/// map compiled under `out` when missing, and no per-sample maps
/// (`compile::glass_shells::load` adds them).
pub fn setup(
    renderer: &mut crate::renderer::Renderer,
    scene: &Scene,
    out: &std::path::Path,
    (tau, deferred): (Option<f32>, bool),
) -> anyhow::Result<()> {
    load_shell(renderer, scene, out)?;
    let Some(glass) = renderer.glass.as_mut() else {
        anyhow::bail!(
            "{}: --mode hybrid needs an object with [objects.glass] (a glass material)",
            scene.origin
        );
    };
    glass.clear_samples();
    glass.deferred = deferred;
    if let Some(tau) = tau {
        let range = inference::scene::glass::GLASS_TAU;
        if !range.contains(&tau) {
            anyhow::bail!("--tau {tau}: expected {range:?} subpixels");
        }
        glass.tau = tau;
    } else if let Some(settings) = scene.objects.iter().find_map(|o| o.glass.as_ref()) {
        glass.tau = settings.tau;
    }
    Ok(())
}

/// Loads the traced room shell map of the scene's glass object (compiled
/// under `out` when missing); a scene without glass needs none.
pub fn load_shell(
    renderer: &mut crate::renderer::Renderer,
    scene: &Scene,
    out: &std::path::Path,
) -> anyhow::Result<()> {
    let Some(g) = renderer.glass.as_ref() else {
        return Ok(());
    };
    let (object, origin, size) = (g.lens.object, g.cube.origin, g.cube.color.desc.width);
    let bytes = shell::room_shell_bytes(scene, out, object, origin, size)?;
    renderer.load_glass_shell(&bytes)?;
    Ok(())
}
