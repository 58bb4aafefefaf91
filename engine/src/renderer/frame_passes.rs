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
use crate::passes::target::{AroundRoom, Load, Target, area_of};
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
        load: Load::Clear,
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

/// The maps' upload (PEM frames), then the reflectors — from
/// parameterized maps, static EMs or REM — and the glass around the lit
/// room. The deferred PEM's G-buffer pass goes first: the depth it lays
/// down spares the room's shading behind the reflectors (about a tenth of
/// the default frame on lavapipe), and its own attachments keep lavapipe
/// from merging it with the room pass, so the timestamps of both hold. The
/// deferred glass's G-buffer goes first in the same way.
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
    let later = Target {
        load: Load::Keep,
        ..target
    };
    let around = reflector_passes(parts, blend, target, view_proj)?;
    // The deferred glass lays the frame's depth first when no reflector
    // pass needs the room before or after it (a mirror drawn over the room
    // in front of the lens would not unmark the lens's pixels).
    let first = around.before_room.is_empty() && around.after_room.is_empty();
    let glass = glass_passes(parts, mode, later, view_proj, first);
    passes.extend(around.before_room);
    passes.extend(glass.before_room);
    let room_load = match (glass.room_load, around.room_load) {
        (Load::ClearColor, _) => Load::ClearColor,
        (_, load) => load,
    };
    passes.push(Box::new(parts.room.pass(
        "room",
        parts.gpu,
        Target {
            load: room_load,
            ..target
        },
        view_proj,
    )));
    passes.extend(around.after_room);
    passes.extend(glass.after_room);
    Ok(passes)
}

/// The glass's passes around the room (none in PEM and REM frames, nor
/// when the lens lies off the frame: an empty render area is invalid).
fn glass_passes<'a>(
    parts: &FrameParts<'a>,
    mode: FrameMode,
    later: Target<'a>,
    view_proj: Mat4,
    first: bool,
) -> AroundRoom<'a> {
    let none = || AroundRoom::after_room(Vec::new());
    let Some(g) = parts
        .glass
        .filter(|_| !matches!(mode, FrameMode::Pem | FrameMode::Rem))
    else {
        return none();
    };
    let area = area_of(view_proj, [g.bounds()], parts.width, parts.height);
    if area.is_some_and(|a| a.extent.width == 0 || a.extent.height == 0) {
        return none();
    }
    g.passes(Target { area, ..later }, view_proj, first)
}

type Passes<'a> = Vec<Box<dyn Pass + 'a>>;

/// The reflectors' passes: REM (its warp first, its shading over the
/// room), the PEM's (deferred: the G-buffer first, which clears depth and
/// stencil, the composite after), or every static EM (after the room).
fn reflector_passes<'a>(
    parts: &FrameParts<'a>,
    blend: Option<&SampleBlend>,
    target: Target<'a>,
    view_proj: Mat4,
) -> GpuResult<AroundRoom<'a>> {
    let later = Target {
        load: Load::Keep,
        ..target
    };
    let (before_room, after_room): (Passes<'a>, Passes<'a>) = if let Some(rem) = parts.rem {
        let (dest, draws) = rem.views.draws(parts.eye);
        let area = area_of(view_proj, [rem.bounds], parts.width, parts.height);
        let shade = rem.gpu.shade_pass(
            parts.gpu,
            Target { area, ..later },
            view_proj,
            parts.eye,
            dest,
        );
        (
            vec![Box::new(rem.gpu.warp_pass(dest, draws))],
            vec![Box::new(shade)],
        )
    } else if let (Some(pem), Some(b)) = (parts.pem, blend) {
        return pem.draw_passes(parts.gpu, parts.gbuffer, b, later, view_proj);
    } else if !parts.reflectors.is_empty() {
        // After the room, although drawing it first measured 5% faster:
        // lavapipe then merges the two passes over the same attachments
        // and its timestamps give the room 0.1 ms for its ~5 ms.
        (
            Vec::new(),
            vec![static_mirror_pass(parts, later, view_proj)],
        )
    } else {
        (Vec::new(), Vec::new())
    };
    // REM's warp renders into its own sphere map, not the frame.
    Ok(AroundRoom {
        before_room,
        room_load: Load::Clear,
        after_room,
    })
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
