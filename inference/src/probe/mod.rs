//! Probe renders: the device that plays the maps back also measures how it
//! samples them. `inference` asks for renders through [`ProbeRenderer`]; the
//! engine implements it on Vulkan with its playback pipelines, so the
//! rendering matrix holds what the device really does (papers.md §1).

mod matrix;
mod schedule;
#[cfg(test)]
mod tests;

pub use matrix::{RenderingMatrix, VerifyReport, build_matrix, build_matrix_with, verify_matrix};
pub use schedule::{ProbeSchedule, ProbeSet};

use crate::solve::layout::TextureLayout;
use glam::{Mat4, Vec2, Vec3};

/// How each vertex addresses the texture.
#[derive(Clone, Debug)]
pub enum Lookup {
    /// 2D texture coordinates (repeat wrap), as a diffuse texture or PTM.
    Uv(Vec<Vec2>),
    /// 2D texture coordinates read from the nearest MIP level only (one
    /// bilinear fetch instead of trilinear's two), as the room's light maps.
    UvNearestLevel(Vec<Vec2>),
    /// Cube-map lookup vectors from CPU texgen (need not be unit length),
    /// read with `lod_bias` added to the level of detail (the reflector's
    /// [`crate::scene::EmSettings::lod_bias`]).
    Cube { dirs: Vec<Vec3>, lod_bias: f32 },
}

impl Lookup {
    /// The texture coordinates of a 2D lookup (`None` for a cube).
    pub fn uvs(&self) -> Option<&[Vec2]> {
        match self {
            Lookup::Uv(uvs) | Lookup::UvNearestLevel(uvs) => Some(uvs),
            Lookup::Cube { .. } => None,
        }
    }
}

/// One object seen from one view: what a probe render draws.
#[derive(Clone, Debug)]
pub struct ProbeGeometry {
    /// Changes whenever positions, indices or lookups change, so a renderer
    /// may keep the uploaded mesh between probes of the same view.
    pub key: u64,
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
    pub lookup: Lookup,
    pub view_proj: Mat4,
    pub width: u32,
    pub height: u32,
}

#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    #[error("probe render failed: {0}")]
    Render(String),
    #[error("{what}: expected {expected}, got {got}")]
    Mismatch {
        what: &'static str,
        expected: String,
        got: String,
    },
    #[error(
        "{pixels} pixels saw two probed texels at once in probe set {set} (probe spacing too small for this device's filter footprint)"
    )]
    Collision { set: usize, pixels: usize },
    #[error(transparent)]
    Solve(#[from] crate::solve::SolveError),
}

/// Renders an object textured with given content, as the engine plays it.
pub trait ProbeRenderer {
    /// Renders `geometry` with `texels` (one RGBA texel per entry of
    /// `layout`, in layout order, every MIP level) through the playback
    /// sampler into a float image of `width × height` pixels, row-major from
    /// the top. RGB = the filtered texture; A = 1 where the object is
    /// visible, 0 elsewhere.
    fn render(
        &mut self,
        geometry: &ProbeGeometry,
        layout: &TextureLayout,
        texels: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError>;
}
