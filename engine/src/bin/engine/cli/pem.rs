//! The playback knobs every playing command shares (`--maps`, `--tau`,
//! `--compositing`, …) and the library's [`PemOptions`] they become.

use super::{parse_tau, parse_view_blend};
use clap::Args;
use engine::backend::Filtering;
use engine::options::{Maps, PemOptions, RoomShading};
use engine::pem::settings::Compositing;
use inference::scene::ViewBlend;
use std::path::PathBuf;

/// Where PEM playback reads maps and the knobs that trade speed for accuracy.
#[derive(Args, Debug, Clone)]
pub struct PemArgs {
    /// Where PEM maps come from: the compressed container (compiled when
    /// missing) or the inferred EXR files.
    #[arg(long, value_enum, default_value_t = Maps::Container)]
    pub maps: Maps,
    /// Play this container (an input: checked against the scene, never
    /// rebuilt) [default: compiled as <out>/<scene>.ptxc].
    #[arg(long)]
    pub container: Option<PathBuf>,
    /// Play the maps `engine infer --all --out DIR` wrote into DIR (an
    /// input: checked, never re-inferred) [default: compiled under <out>/infer].
    #[arg(long)]
    pub infer_dir: Option<PathBuf>,
    /// Draw the nearest viewpoint sample only (no blend pass).
    #[arg(long)]
    pub no_blend: bool,
    /// Layered PEM: the distant layer only (no local layer).
    #[arg(long)]
    pub distant_only: bool,
    /// Use every Nth viewpoint sample only.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub spacing: u32,
    /// How a view between rings weighs the samples around it: the three
    /// corners of the triangle of samples that holds it (`triangles`), or
    /// the four corners of its grid cell (`bilinear`: one cube lookup per
    /// layer more).
    #[arg(long, value_parser = parse_view_blend, default_value = "triangles")]
    pub view_blend: ViewBlend,
    /// EM resolution to play (a power of two up to the inferred one; lower
    /// sizes use the inferred maps' coarser MIP levels) [default: inferred].
    #[arg(long)]
    pub em_size: Option<u32>,
    /// Texture filtering of the maps.
    #[arg(long, value_enum, default_value_t = Filtering::Trilinear)]
    pub filtering: Filtering,
    /// How blended samples and layers are composited: `deferred` shades
    /// each covered pixel once (reflectors, and glass blending per-sample
    /// shell maps); `multipass` is the papers' one pass per sample,
    /// blended (glass: one forward pass over the lens).
    #[arg(long, value_enum, default_value_t = Compositing::Deferred)]
    pub compositing: Compositing,
    /// Deferred compositing: the tracer's film filter (a Gaussian of ½
    /// pixel) along the reflectors' outlines, where rasterized frames step
    /// from one pixel to the next: about +0.2 dB over the frame for
    /// 1.06–1.09× its time (two more passes).
    #[arg(long)]
    pub edge_filter: bool,
    /// Hybrid glass: split triangles whose vertex ray paths differ until
    /// their projected edges are below TAU subpixels (⅓ pixel) [default:
    /// the scene's `[objects.glass] tau`].
    #[arg(long, value_parser = parse_tau)]
    pub tau: Option<f32>,
    /// Hybrid glass: play the one traced room shell map even where the
    /// scene asks for per-sample shell maps (`[objects.glass] shell_every`).
    #[arg(long)]
    pub traced_shell: bool,
    /// Hybrid glass with layered shells: play the traced layer maps, the
    /// same for every view, even where the scene asks for per-sample maps.
    #[arg(long)]
    pub traced_layers: bool,
    /// How the room is lit in the PEM, PTM, REM and hybrid glass modes:
    /// `inferred` light maps of the traced light (compiled with the maps,
    /// cached under `<out>/room/`) or the `analytic` point light plus
    /// ambient (what the static-EM baseline always draws).
    #[arg(long, value_enum, default_value_t = RoomShading::Inferred)]
    pub room: RoomShading,
    /// `--mode rem`: resolution of the traced source sphere maps.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(4..=2048))]
    pub rem_size: u32,
    /// `--mode rem`: icosahedron subdivisions (0: 12 source views, 1: 42).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=3))]
    pub rem_level: u32,
}

impl PemArgs {
    pub fn options(&self) -> PemOptions {
        PemOptions {
            maps: self.maps,
            container: self.container.clone(),
            infer_dir: self.infer_dir.clone(),
            blend: !self.no_blend,
            local_layer: !self.distant_only,
            spacing: self.spacing,
            view_blend: self.view_blend,
            em_size: self.em_size,
            filtering: self.filtering,
            compositing: self.compositing,
            edge_filter: self.edge_filter,
            tau: self.tau,
            traced_shell: self.traced_shell,
            traced_layers: self.traced_layers,
            room: self.room,
            rem_size: self.rem_size,
            rem_level: self.rem_level,
        }
    }
}
