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
    let view = layer_view(tracer, lens, shells, eye, s, |i| key + i)?;
    let [t, r] = (view.shells.into_iter().next()).context("the room shell set has no shell")?;
    Ok(FrameView {
        t,
        r,
        targets: view.targets,
        beauty: view.beauty,
    })
}

/// One view of a layered solve: the traced targets (each term's image of
/// every shell), per shell the two terms' probe geometry (T, R), and the
/// whole frame traced independently (RGB per pixel).
pub struct LayerView {
    pub targets: inference::glass::targets::GlassTargets,
    pub shells: Vec<[ProbeGeometry; 2]>,
    pub beauty: Vec<[f32; 3]>,
}

/// The view from `eye` for every shell of `shells`; `key(i)` names probe
/// mesh `i` (2·shell + term), unique per view of one solve.
pub fn layer_view(
    tracer: &Tracer,
    lens: &Lens,
    shells: &ShellSet,
    eye: Vec3,
    s: ViewSettings,
    key: impl Fn(u64) -> u64,
) -> Result<LayerView> {
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
    let beauty = beauty(tracer, eye, &settings)?;
    let geometry = |shell: usize, term: Term, i: u64| ProbeGeometry {
        key: key(i),
        positions: tess.positions.clone(),
        indices: tess.indices.clone(),
        lookup: Lookup::Cube {
            dirs: term_lookups(&tess, shells, term, shell),
            lod_bias: 0.0,
        },
        view_proj,
        width,
        height,
    };
    let shells = (0..shells.shells.len())
        .map(|k| {
            let i = 2 * k as u64;
            [geometry(k, Term::T, i), geometry(k, Term::R, i + 1)]
        })
        .collect();
    Ok(LayerView {
        targets,
        shells,
        beauty,
    })
}

/// The whole frame from `eye` traced at `settings` with the solve's own
/// seed, RGB per pixel.
fn beauty(tracer: &Tracer, eye: Vec3, settings: &TraceSettings) -> Result<Vec<[f32; 3]>> {
    let frame = tracer.render(
        eye,
        &TraceSettings {
            seed: SOLVE_FRAME_SEED,
            ..settings.clone()
        },
    )?;
    let beauty = frame
        .layer("beauty")
        .context("the traced frame has no beauty layer")?;
    Ok(beauty
        .pixels
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect())
}
