//! Frames in flight for PEM frames: the next frame's texgen streams and
//! compositing bands, computed on a worker while the device renders this
//! frame. lavapipe keeps only part of the two cores busy while it renders
//! (its triangle set-up is one thread), and the ~1.2 ms of CPU work a PEM
//! frame needs before it can be recorded fits in what it leaves idle. The
//! result is used only for exactly the view and settings it was made for.

use super::settings::{PemKind, PemSettings};
use ash::vk;
use glam::{Mat4, Vec3};
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

    /// Texgen of one stream for `eye`.
    fn stream(&self, geometry: &EmGeometry, eye: Vec3) -> Vec<TexgenVertex> {
        let mut out = vec![[0.0; 4]; self.positions.len()];
        texgen(
            geometry,
            self.origin,
            eye,
            self.positions,
            self.normals,
            &mut out,
        );
        out
    }

    /// The compositing bands of the frame `view_proj` (only deferred
    /// frames draw by bands; empty: draw the bounding rectangle).
    fn bands(&self, request: &TexgenRequest) -> Vec<vk::Rect2D> {
        request
            .settings
            .deferred()
            .then(|| {
                crate::passes::bands::screen_bands(
                    request.view_proj,
                    self.positions,
                    self.triangles,
                    request.size,
                    &mut Vec::new(),
                )
            })
            .flatten()
            .unwrap_or_default()
    }

    /// Everything `request` needs: the streams and, beside them on
    /// rayon's other thread, the bands.
    pub fn compute(&self, request: TexgenRequest) -> TexgenFrame {
        let (streams, bands) = rayon::join(
            || {
                self.geometries(&request.settings)
                    .iter()
                    .map(|g| self.stream(g, request.eye))
                    .collect()
            },
            || self.bands(&request),
        );
        TexgenFrame {
            request,
            streams,
            bands,
        }
    }
}
