//! What a run of the engine is asked to do, as typed values: the drivers
//! (play, bench, eval, compile) take these, the binary's command line
//! builds them, and drivers build them for each other — never argv.

use crate::backend::{DeviceOptions, Filtering};
use crate::pem::settings::Compositing;
use inference::scene::ViewBlend;
use std::path::PathBuf;

/// What each frame draws.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Mirror reflectors from one static cube map (the baseline).
    StaticEm,
    /// One inferred sphere-at-infinity EM per viewpoint sample.
    SpherePem,
    /// Inferred distant (box) and local (ellipsoid) EMs per sample (the PEM paper).
    LayeredPem,
    /// Inferred parameterized texture maps pasted on the surface.
    Ptm,
    /// The ray-traced gold standard (CPU, seconds per frame).
    Trace,
    /// Every mesh with one texture and nothing else (reference cost).
    Bare,
    /// Glass by hybrid rendering: CPU ray paths through the glass at the
    /// vertices of an adaptive tessellation, exit rays into a shell map.
    Hybrid,
    /// Reflection-space IBR: traced radiance sphere maps at the vertices of
    /// an icosahedron of views, warped and blended per frame.
    Rem,
}

impl Mode {
    /// The flag value, e.g. `layered-pem`.
    pub fn name(self) -> &'static str {
        match self {
            Mode::StaticEm => "static-em",
            Mode::SpherePem => "sphere-pem",
            Mode::LayeredPem => "layered-pem",
            Mode::Ptm => "ptm",
            Mode::Trace => "trace",
            Mode::Bare => "bare",
            Mode::Hybrid => "hybrid",
            Mode::Rem => "rem",
        }
    }

    /// The mode a scene plays when none is asked for: hybrid for a scene
    /// with a glass object, layered PEMs otherwise.
    pub fn default_for(scene: &inference::scene::Scene) -> Mode {
        if scene.objects.iter().any(|o| o.glass.is_some()) {
            Mode::Hybrid
        } else {
            Mode::LayeredPem
        }
    }
}

/// How the diffuse room is lit in the PEM, PTM, REM and hybrid glass modes.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RoomShading {
    /// Each diffuse object's albedo × its inferred light map (the traced
    /// light, compiled with the maps: `compile::room`).
    Inferred,
    /// The area light as a point emitter plus a constant ambient (no
    /// shadows): the real-time approximation, kept for comparison.
    Analytic,
}

/// Where PEM playback reads its maps.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Maps {
    /// The compressed container (compiled when missing).
    Container,
    /// The inferred EXR maps themselves (uncompressed).
    Exr,
}

/// PEM playback's inputs and the knobs that trade speed for accuracy.
#[derive(Clone, Debug, PartialEq)]
pub struct PemOptions {
    pub maps: Maps,
    /// A container to play instead of the one compiled under the output
    /// folder (read only: never rebuilt).
    pub container: Option<PathBuf>,
    /// Inferred maps to play instead of those compiled under the output
    /// folder (read only: never re-inferred).
    pub infer_dir: Option<PathBuf>,
    /// Blend the two nearest samples (false: nearest only).
    pub blend: bool,
    /// Layered PEMs: the local layer too (false: distant only).
    pub local_layer: bool,
    /// Use every Nth viewpoint sample only (1: all).
    pub spacing: u32,
    /// How a view between rings weighs the samples around it.
    pub view_blend: ViewBlend,
    /// EM resolution to play (a power of two up to the inferred one).
    pub em_size: Option<u32>,
    pub filtering: Filtering,
    /// How blended samples and layers are composited.
    pub compositing: Compositing,
    /// Deferred compositing: the tracer's film filter along the
    /// reflectors' outlines.
    pub edge_filter: bool,
    /// Hybrid glass: tessellation threshold in subpixels [default: the
    /// scene's `[objects.glass] tau`].
    pub tau: Option<f32>,
    /// Hybrid glass: the one traced shell map, not the per-sample ones.
    pub traced_shell: bool,
    /// Hybrid glass with layered shells: the traced layer maps, not the
    /// per-sample ones.
    pub traced_layers: bool,
    /// How the room is lit.
    pub room: RoomShading,
    /// Reflection-space IBR: source sphere-map resolution.
    pub rem_size: u32,
    /// Reflection-space IBR: subdivisions of the icosahedron of views.
    pub rem_level: u32,
}

impl Default for PemOptions {
    fn default() -> Self {
        Self {
            maps: Maps::Container,
            container: None,
            infer_dir: None,
            blend: true,
            local_layer: true,
            spacing: 1,
            view_blend: ViewBlend::default(),
            em_size: None,
            filtering: Filtering::Trilinear,
            compositing: Compositing::Deferred,
            edge_filter: false,
            tau: None,
            traced_shell: false,
            traced_layers: false,
            room: RoomShading::Inferred,
            rem_size: crate::rem::sources::RemSettings::default().size,
            rem_level: 0,
        }
    }
}

impl PemOptions {
    /// The main command's flags that differ from the defaults, e.g.
    /// `--no-blend --spacing 4` (so a row of the eval table can be replayed).
    pub fn flags(&self) -> Vec<(String, Option<String>)> {
        let d = PemOptions::default();
        let mut f = Vec::new();
        if self.maps != d.maps {
            f.push(("maps".into(), Some("exr".into())));
        }
        if !self.blend {
            f.push(("no-blend".into(), None));
        }
        if !self.local_layer {
            f.push(("distant-only".into(), None));
        }
        if self.spacing != d.spacing {
            f.push(("spacing".into(), Some(self.spacing.to_string())));
        }
        if self.view_blend != d.view_blend {
            f.push(("view-blend".into(), Some(self.view_blend.name().into())));
        }
        if let Some(s) = self.em_size {
            f.push(("em-size".into(), Some(s.to_string())));
        }
        if self.filtering != d.filtering {
            f.push(("filtering".into(), Some(self.filtering.name().into())));
        }
        if self.compositing != d.compositing {
            f.push(("compositing".into(), Some("multipass".into())));
        }
        if self.edge_filter {
            f.push(("edge-filter".into(), None));
        }
        if let Some(tau) = self.tau {
            f.push(("tau".into(), Some(tau.to_string())));
        }
        if self.traced_shell {
            f.push(("traced-shell".into(), None));
        }
        if self.traced_layers {
            f.push(("traced-layers".into(), None));
        }
        if self.room != d.room {
            f.push(("room".into(), Some("analytic".into())));
        }
        if self.rem_size != d.rem_size {
            f.push(("rem-size".into(), Some(self.rem_size.to_string())));
        }
        if self.rem_level != d.rem_level {
            f.push(("rem-level".into(), Some(self.rem_level.to_string())));
        }
        f
    }
}

/// Where a run happens: the scene, the output folder, the device, the
/// frame size.
#[derive(Clone, Debug)]
pub struct RunPlace {
    /// A built-in scene name or a scene file path, as the user gave it
    /// (hints name it the same way).
    pub scene: String,
    /// The output folder [default: `out/<scene>`].
    pub out: Option<PathBuf>,
    pub device: DeviceOptions,
    pub size: (u32, u32),
    /// Ignore the compiled data shipped in `assets/compiled/` and compile
    /// everything missing under the output folder.
    pub recompile: bool,
}

impl RunPlace {
    /// A run of `scene` playing what is compiled in `out` (or shipped for
    /// it) at `size`, on the default device, compiling nothing again: what
    /// the examples that score one view open.
    pub fn compiled_in(scene: &str, out: &std::path::Path, size: (u32, u32)) -> Self {
        RunPlace {
            scene: scene.to_string(),
            out: Some(out.to_path_buf()),
            device: Default::default(),
            size,
            recompile: false,
        }
    }

    /// The output folder: as given, else `out/<scene>` under the current
    /// folder.
    pub fn out_dir(&self, scene: &inference::scene::Scene) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| PathBuf::from("out").join(&scene.name))
    }
}

/// The main job: what to draw along the default path, and what to keep.
#[derive(Clone, Debug)]
pub struct PlayOptions {
    /// None: the scene's default ([`Mode::default_for`]).
    pub mode: Option<Mode>,
    pub pem: PemOptions,
    /// Frames along the default path [default: 1.5 per viewpoint sample].
    pub frames: Option<u32>,
    /// Untimed frames first (lavapipe compiles shaders at the first draw).
    pub warmup: u32,
    /// Write each frame as PNG (false: only perf.json).
    pub capture: bool,
    /// Also write each frame as linear float EXR.
    pub exr: bool,
    /// With `capture`: also write the path as a video (`crate::video`).
    pub video: bool,
    /// How `Mode::Trace` frames are traced.
    pub trace: TraceFrames,
    /// A light that moves along the path (static-EM frames, the reflector
    /// showing the room relit for it).
    pub light_path: Option<LightPathOptions>,
}

/// `Mode::Trace` frames: samples per pixel and the tracer's seed (another
/// seed traces an independent image of the same view: what a reference's
/// noise alone scores against it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceFrames {
    pub spp: u32,
    pub seed: u64,
}

impl Default for TraceFrames {
    fn default() -> Self {
        Self { spp: 16, seed: 0 }
    }
}

/// `--light-path`: which path, and the relightable panorama it plays
/// (`relight::GridSettings`: size, light grid, samples per texel).
#[derive(Clone, Copy, Debug)]
pub struct LightPathOptions {
    pub path: crate::relight::light_path::LightPath,
    pub size: (u32, u32),
    pub grid: (u32, u32),
    pub spp: u32,
}

impl PlayOptions {
    pub fn new(mode: Mode) -> Self {
        Self {
            mode: Some(mode),
            pem: PemOptions::default(),
            frames: None,
            warmup: 3,
            capture: true,
            exr: false,
            video: true,
            trace: TraceFrames::default(),
            light_path: None,
        }
    }
}

/// `--filtering trilinear|bilinear|nearest`.
impl clap::ValueEnum for Filtering {
    fn value_variants<'a>() -> &'a [Self] {
        &Filtering::ALL
    }
    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}
