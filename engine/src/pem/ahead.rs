//! Frames in flight for PEM frames: the next frame's texgen streams and
//! compositing bands, computed on a worker while the device renders this
//! frame. lavapipe keeps only part of the two cores busy while it renders
//! (its triangle set-up is one thread), and the ~1.2 ms of CPU work a PEM
//! frame needs before it can be recorded fits in what it leaves idle. The
//! result is used only for exactly the view and settings it was made for.

use super::settings::{PemKind, PemSettings};
use ash::vk;
use glam::{Mat4, Vec2, Vec3};
use inference::em_geometry::{EmGeometry, texgen};
use inference::texgen::TexgenVertex;

/// What one reflector's texgen and bands depend on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexgenRequest {
    pub eye: Vec3,
    pub view_proj: Mat4,
    pub size: (u32, u32),
    pub settings: PemSettings,
}

/// One reflector's texgen streams (distant, then local when drawn) and
/// compositing bands for one request.
pub struct TexgenFrame {
    pub request: TexgenRequest,
    pub streams: Vec<Vec<TexgenVertex>>,
    pub bands: Vec<vk::Rect2D>,
}

/// What a reflector's texgen reads: its mesh and EM geometries, borrowed.
#[derive(Clone, Copy)]
pub struct TexgenInputs<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub triangles: &'a [u32],
    pub origin: Vec3,
    pub distant: EmGeometry,
    pub local: EmGeometry,
}

impl TexgenInputs<'_> {
    /// The EM geometries whose streams `settings` draw, in stream order
    /// (none for PTMs, which need no texgen).
    pub fn geometries(&self, settings: &PemSettings) -> Vec<EmGeometry> {
        match settings.kind {
            PemKind::Ptm => Vec::new(),
            PemKind::Sphere => vec![EmGeometry::SphereAtInfinity],
            PemKind::Layered if settings.local_layer => vec![self.distant, self.local],
            PemKind::Layered => vec![self.distant],
        }
    }

    /// Texgen of one stream for `eye` into `out`.
    pub fn stream(&self, geometry: &EmGeometry, eye: Vec3, out: &mut Vec<TexgenVertex>) {
        out.resize(self.positions.len(), [0.0; 4]);
        texgen(
            geometry,
            self.origin,
            eye,
            self.positions,
            self.normals,
            out,
        );
    }

    /// The compositing bands of the frame `view_proj` (only deferred
    /// frames draw by bands; empty: draw the bounding rectangle).
    pub fn bands(&self, request: &TexgenRequest, pixels: &mut Vec<Vec2>) -> Vec<vk::Rect2D> {
        request
            .settings
            .deferred()
            .then(|| {
                super::bands::screen_bands(
                    request.view_proj,
                    self.positions,
                    self.triangles,
                    request.size,
                    pixels,
                )
            })
            .flatten()
            .unwrap_or_default()
    }

    /// Everything `request` needs, on the calling thread.
    pub fn compute(&self, request: TexgenRequest) -> TexgenFrame {
        let streams = self
            .geometries(&request.settings)
            .iter()
            .map(|g| {
                let mut out = Vec::new();
                self.stream(g, request.eye, &mut out);
                out
            })
            .collect();
        let bands = self.bands(&request, &mut Vec::new());
        TexgenFrame {
            request,
            streams,
            bands,
        }
    }
}
