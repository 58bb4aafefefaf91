//! The Utah teapot from Newell's 32 bicubic Bézier patches: data and tessellation.

mod data;
mod patch;
mod tessellate;
mod weld;

#[cfg(test)]
mod tests;

pub use patch::{Patch, Sample};
pub use tessellate::{MAX_SEGMENTS, Tessellation, tessellate};

/// Height of the model in original units (bottom pole at 0, lid knob top at 3.15).
pub const HEIGHT: f32 = 3.15;

/// Default segments per patch edge: 64·25² − 8·25 = 39,800 triangles, the PEM paper's ~40k.
pub const DEFAULT_SEGMENTS: u32 = 25;

/// Which patches to tessellate. The PEM paper gives lid and body their own EMs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TeapotPart {
    #[default]
    Whole,
    /// Rim, body, handle, spout and bottom.
    Body,
    /// Lid knob and lid.
    Lid,
}

impl TeapotPart {
    pub fn patches(self) -> Vec<usize> {
        match self {
            TeapotPart::Whole => (0..32).collect(),
            TeapotPart::Body => (0..20).chain(28..32).collect(),
            TeapotPart::Lid => (20..28).collect(),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            TeapotPart::Whole => "whole",
            TeapotPart::Body => "body",
            TeapotPart::Lid => "lid",
        }
    }
}
