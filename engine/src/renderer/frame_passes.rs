//! The pass list of one frame: only the passes its mode and the scene need,
//! ending with the read-back of the frame colour.

use super::FrameMode;
use super::reflectors::Reflector;
use crate::backend::{Buffer, Device, GpuResult, Image};
use crate::glass::GlassPlayer;
use crate::gpu_scene::GpuScene;
use crate::graph::Pass;
use crate::passes::mirror::MirrorRenderer;
use crate::passes::pem_deferred::GBuffer;
use crate::passes::readback::ReadbackPass;
use crate::passes::room::RoomRenderer;
use crate::passes::target::{Target, area_of};
use crate::pem::player::PemPlayer;
use crate::pem::samples::SampleBlend;
use ash::vk;
use glam::Mat4;

/// The renderer's fields a frame's passes read, borrowed one by one (not
/// through `&Renderer`): the executor, another field, must stay free to be
/// borrowed mutably while it runs these passes.
pub(super) struct FrameParts<'a> {
    pub(super) device: &'a Device,
    pub(super) gpu: &'a GpuScene,
    pub(super) room: &'a RoomRenderer,
    pub(super) bare: &'a RoomRenderer,
    pub(super) mirror: &'a MirrorRenderer,
    pub(super) reflectors: &'a [Reflector],
    pub(super) pem: Option<&'a PemPlayer>,
    /// Set in REM frames only.
    pub(super) rem: Option<&'a crate::rem::RemPlayer>,
    /// Set in static-EM frames under `--light-path` only.
    pub(super) light_path: Option<&'a super::light_path::LightPathGpu>,
    pub(super) eye: glam::Vec3,
    pub(super) gbuffer: &'a GBuffer,
    pub(super) glass: Option<&'a GlassPlayer>,
    pub(super) color: &'a Image,
    pub(super) depth: &'a Image,
    pub(super) readback: &'a Buffer,
    pub(super) width: u32,
    pub(super) height: u32,
}

/// Every pass of a `mode` frame seen through `view_proj`; `blend` is the
/// PEM frame's samples (None in other modes).
pub(super) fn frame_passes<'a>(
    parts: &FrameParts<'a>,
    mode: FrameMode,
    blend: Option<&SampleBlend>,
    view_proj: Mat4,
) -> GpuResult<Vec<Box<dyn Pass + 'a>>> {
    let target = Target {
        color: parts.color,
        depth: parts.depth,
        level: 0,
        layer: 0,
        clear: true,
        front_face: vk::FrontFace::COUNTER_CLOCKWISE,
        area: None,
    };
    let mut passes: Vec<Box<dyn Pass + 'a>> = match mode {
        FrameMode::StaticEm | FrameMode::Pem | FrameMode::Hybrid | FrameMode::Rem => {
            lit_passes(parts, mode, blend, target, view_proj)?
        }
        FrameMode::Bare => vec![Box::new(
            parts.bare.pass("bare", parts.gpu, target, view_proj),
        )],
    };
    passes.push(Box::new(ReadbackPass {
        device: parts.device,
        image: parts.color,
        buffer: parts.readback,
    }));
    Ok(passes)
}

/// The lit room (after the upload of the maps a PEM frame read), then the
/// reflectors — from parameterized maps or static EMs — and the glass.
fn lit_passes<'a>(
    parts: &FrameParts<'a>,
    mode: FrameMode,
    blend: Option<&SampleBlend>,
    target: Target<'a>,
    view_proj: Mat4,
) -> GpuResult<Vec<Box<dyn Pass + 'a>>> {
    let mut passes: Vec<Box<dyn Pass + 'a>> = Vec::new();
    let upload = match (parts.pem, mode) {
        (Some(pem), FrameMode::Pem) => pem.upload_pass()?,
        _ => None,
    };
    if let Some(upload) = upload {
        passes.push(Box::new(upload));
    }
    if let Some(lp) = parts.light_path {
        passes.extend(lp.passes(parts.device, parts.reflectors));
    }
    let rem = parts.rem.map(|rem| (rem, rem.views.draws(parts.eye)));
    if let Some((rem, (dest, draws))) = &rem {
        passes.push(Box::new(rem.gpu.warp_pass(*dest, draws.clone())));
    }
    passes.push(Box::new(
        parts.room.pass("room", parts.gpu, target, view_proj),
    ));
    let later = Target {
        clear: false,
        ..target
    };
    if let Some((rem, (dest, _))) = rem {
        let area = area_of(view_proj, [rem.bounds], parts.width, parts.height);
        let target = Target { area, ..later };
        passes.push(Box::new(
            rem.gpu
                .shade_pass(parts.gpu, target, view_proj, parts.eye, dest),
        ));
    } else if let (Some(pem), Some(b)) = (parts.pem, blend) {
        passes.extend(pem.draw_passes(parts.gpu, parts.gbuffer, b, later, view_proj)?);
    } else if !parts.reflectors.is_empty() {
        passes.push(static_mirror_pass(parts, later, view_proj));
    }
    if let Some(g) = parts
        .glass
        .filter(|_| !matches!(mode, FrameMode::Pem | FrameMode::Rem))
    {
        let area = area_of(view_proj, [g.bounds()], parts.width, parts.height);
        passes.push(Box::new(g.pass(Target { area, ..later }, view_proj)));
    }
    Ok(passes)
}

/// Every reflector from its static EM, in one pass limited to their
/// screen-space bounds.
fn static_mirror_pass<'a>(
    parts: &FrameParts<'a>,
    later: Target<'a>,
    view_proj: Mat4,
) -> Box<dyn Pass + 'a> {
    let area = area_of(
        view_proj,
        parts.reflectors.iter().map(|r| r.bounds),
        parts.width,
        parts.height,
    );
    Box::new(parts.mirror.pass(
        parts.gpu,
        parts.reflectors.iter().map(|r| &r.draw).collect(),
        parts.reflectors.iter().map(|r| &r.cube.color).collect(),
        Target { area, ..later },
        view_proj,
    ))
}
