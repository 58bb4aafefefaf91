//! What PEM playback draws: the kind of maps and the knobs that trade speed
//! for accuracy.

use super::source::MapLayer;
use crate::backend::Filtering;
use inference::scene::ViewBlend;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PemSettings {
    pub kind: PemKind,
    /// Layered PEMs: draw the local layer (false = distant layer only).
    pub local_layer: bool,
    /// Blend the two nearest samples (false = nearest only).
    pub blend: bool,
    /// Use every `spacing`-th sample only (1 = all).
    pub spacing: u32,
    /// How a view between rings weighs the samples around it.
    pub view_blend: ViewBlend,
    /// Finest MIP levels dropped: the EM resolution is `res >> drop_levels`.
    pub drop_levels: u32,
    pub filtering: Filtering,
    /// How blended samples are composited (PTMs always draw multipass).
    pub compositing: Compositing,
    /// Deferred frames: the tracer's film filter along the reflectors'
    /// outlines (`passes::edge_filter`; off by default: +0.2 dB over the
    /// frame for 1.06–1.09× its time).
    pub edge_filter: bool,
    /// Decoded maps go through staging buffers and an upload pass even
    /// where the device could sample them where they are decoded (host-
    /// written slot arrays, lavapipe): what a GPU does, kept for comparison.
    pub staging_uploads: bool,
}

/// How a frame composites its EM layers and blended samples.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Compositing {
    /// Reflectors rasterized once into per-pixel lookups, then each covered
    /// pixel shaded once from every layer of every blended sample.
    Deferred,
    /// The papers' formulation: the reflector drawn once per blended sample,
    /// each pass blended over the last by its weight.
    Multipass,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PemKind {
    /// Distant box + local ellipsoid layers (the PEM paper's method).
    Layered,
    /// One sphere-at-infinity EM per sample.
    Sphere,
    /// Parameterized texture maps on the surface.
    Ptm,
}

impl PemSettings {
    pub fn new(kind: PemKind) -> Self {
        Self {
            kind,
            local_layer: true,
            blend: true,
            spacing: 1,
            view_blend: ViewBlend::default(),
            drop_levels: 0,
            filtering: Filtering::Trilinear,
            compositing: Compositing::Deferred,
            edge_filter: false,
            staging_uploads: false,
        }
    }

    /// Whether frames composite deferred (PTMs cannot: they are 2D maps).
    pub fn deferred(&self) -> bool {
        self.compositing == Compositing::Deferred && self.kind != PemKind::Ptm
    }

    /// The maps one sample needs, in slot order.
    pub fn layers(&self) -> Vec<MapLayer> {
        match self.kind {
            PemKind::Layered if self.local_layer => vec![MapLayer::Distant, MapLayer::Local],
            PemKind::Layered => vec![MapLayer::Distant],
            PemKind::Sphere => vec![MapLayer::Sphere],
            PemKind::Ptm => vec![MapLayer::Ptm],
        }
    }
}
