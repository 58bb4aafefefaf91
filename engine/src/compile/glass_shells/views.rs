//! One view of a per-sample shell solve: the lens tessellated to τ from the
//! eye, each vertex's two exit-ray lookups into the room shell (the probe
//! geometry of the two terms), the traced per-term weights and coverage,
//! and the whole frame traced independently (another seed than the
//! eval's references).

use super::solve::FrameView;
use anyhow::{Context, Result};
use glam::Vec3;
use inference::glass::targets::trace_targets;
use inference::glass::vertices::{Term, term_lookups};
use inference::glass::{Lens, Screen, ShellSet, TessSettings, tessellate};
use inference::probe::{Lookup, ProbeGeometry};
use inference::trace::{TraceSettings, Tracer, camera};

/// The seed of the frames the shell maps are solved against: not the
/// maps' traces' (0), not the eval's references'
/// (`crate::eval::reference::REFERENCE_SEED`).
pub const SOLVE_FRAME_SEED: u64 = 1;

/// How a view is traced and tessellated.
#[derive(Clone, Copy, Debug)]
pub struct ViewSettings {
    pub size: (u32, u32),
    pub spp: u32,
    /// τ of the probe geometry, subpixels.
    pub tau: f32,
}

/// The view from `eye`; `key` names its refraction term's probe mesh and
/// `key + 1` its reflection term's (unique per view of one solve).
pub fn frame_view(
    tracer: &Tracer,
    lens: &Lens,
    shells: &ShellSet,
    eye: Vec3,
    s: ViewSettings,
    key: u64,
) -> Result<FrameView> {
    let scene = tracer.scene();
    let (width, height) = s.size;
    let view_proj = camera::projection(scene, width, height) * scene.orbit.view(eye);
    let screen = Screen {
        view_proj,
        width,
        height,
    };
    let tess = tessellate(lens, eye, screen, TessSettings::new(s.tau));
    let settings = TraceSettings {
        width,
        height,
        spp: s.spp,
        ..TraceSettings::default()
    };
    let targets = trace_targets(tracer, lens, shells, eye, &settings);
    let frame = tracer.render(
        eye,
        &TraceSettings {
            seed: SOLVE_FRAME_SEED,
            ..settings
        },
    )?;
    let beauty = frame
        .layer("beauty")
        .context("the traced frame has no beauty layer")?;
    let geometry = |term, key| ProbeGeometry {
        key,
        positions: tess.positions.clone(),
        indices: tess.indices.clone(),
        lookup: Lookup::Cube {
            dirs: term_lookups(&tess, shells, term, 0),
            lod_bias: 0.0,
        },
        view_proj,
        width,
        height,
    };
    Ok(FrameView {
        t: geometry(Term::T, key),
        r: geometry(Term::R, key + 1),
        targets,
        beauty: beauty
            .pixels
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect(),
    })
}
