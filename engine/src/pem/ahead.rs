//! Frames in flight for PEM frames: the next frame's texgen streams,
//! compositing bands and outline tiles, computed on a worker while the
//! device renders this frame. lavapipe keeps only part of the two cores
//! busy while it renders (its triangle set-up is one thread), and the CPU
//! work a PEM frame needs before it can be recorded (about 0.6 ms for the
//! teapot) fits in what it leaves idle. The result is used only for
//! exactly the view and settings it was made for. Texgen runs only on the
//! vertices of the triangles that may face the eye ([`super::facing`]),
//! the only ones the frame draws.

use super::facing::{Facing, FacingMesh};
use super::settings::{PemKind, PemSettings};
use crate::passes::bands::{bands_of, project};
use crate::passes::outline::MeshEdges;
use ash::vk;
use glam::{Mat4, Vec2, Vec3};
use inference::em_geometry::{EmGeometry, texgen_where};
use inference::texgen::TexgenVertex;

/// What one reflector's texgen and bands depend on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexgenRequest {
    pub eye: Vec3,
    pub view_proj: Mat4,
    pub size: (u32, u32),
    pub settings: PemSettings,
}

/// One reflector's triangles facing the eye, its texgen streams of their
/// vertices (distant, then local when drawn), compositing bands and
/// outline tiles for one request.
pub struct TexgenFrame {
    pub request: TexgenRequest,
    pub facing: Facing,
    pub streams: Vec<Vec<TexgenVertex>>,
    pub screen: ScreenParts,
}

/// Where a reflector lies on one frame's screen: its compositing bands
/// (empty where no bound holds: draw the bounding rectangle) and, for the
/// edge filter, the tiles its outline can reach (then the whole frame).
#[derive(Default)]
pub struct ScreenParts {
    pub bands: Vec<vk::Rect2D>,
    pub outline: Vec<vk::Rect2D>,
}

/// What a reflector's texgen reads: its mesh and EM geometries, borrowed.
#[derive(Clone, Copy)]
pub struct TexgenInputs<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub triangles: &'a [u32],
    /// Its triangles in draw order (hull first), which a view culls.
    pub facing: &'a FacingMesh,
    /// The mesh's edges, when the edge filter asks for outline tiles.
    pub edges: Option<&'a MeshEdges>,
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

    /// Texgen of one stream for `eye`, on the `used` vertices (the others
    /// stay zero: no drawn triangle reads them).
    fn stream(&self, geometry: &EmGeometry, eye: Vec3, used: &[bool]) -> Vec<TexgenVertex> {
        let mut out = vec![[0.0; 4]; self.positions.len()];
        texgen_where(
            geometry,
            (self.origin, eye),
            (self.positions, self.normals),
            used,
            &mut out,
        );
        out
    }

    /// The compositing bands (of the triangles `facing` keeps: the others
    /// are not drawn) and outline tiles of a frame whose vertices land at
    /// `pixels` (None: no screen bound holds); only deferred frames draw
    /// by them.
    fn screen(
        &self,
        request: &TexgenRequest,
        pixels: Option<&[Vec2]>,
        facing: &Facing,
    ) -> ScreenParts {
        if !request.settings.deferred() {
            return ScreenParts::default();
        }
        let bands = pixels.and_then(|p| bands_of(p, &facing.indices, request.size));
        let filter = request.settings.edge_filter;
        let outline = match (pixels, &bands, self.edges) {
            (Some(pixels), Some(_), Some(edges)) if filter => {
                edges.outline_tiles(pixels, self.triangles, request.size)
            }
            _ => None,
        };
        // Where no bound holds, the filter runs over the whole frame.
        let (width, height) = request.size;
        let whole = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D { width, height },
        };
        ScreenParts {
            bands: bands.unwrap_or_default(),
            outline: match outline {
                Some(tiles) => tiles,
                None if filter => vec![whole],
                None => Vec::new(),
            },
        }
    }

    /// Everything `request` needs: where the vertices land on screen, the
    /// triangles that may face the eye there, then their vertices' streams
    /// and, beside them on rayon's other thread, the bands and outline
    /// tiles.
    pub fn compute(&self, request: TexgenRequest) -> TexgenFrame {
        let mut pixels = Vec::new();
        let on_screen = project(request.view_proj, self.positions, request.size, &mut pixels);
        let pixels = on_screen.map(|()| pixels.as_slice());
        let facing = self.facing.facing(pixels);
        let (streams, screen) = rayon::join(
            || {
                self.geometries(&request.settings)
                    .iter()
                    .map(|g| self.stream(g, request.eye, &facing.used))
                    .collect()
            },
            || self.screen(&request, pixels, &facing),
        );
        TexgenFrame {
            request,
            facing,
            streams,
            screen,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad in front of or around the eye, its inputs and a request.
    fn screen_of(z: f32, edge_filter: bool) -> ScreenParts {
        let positions: Vec<Vec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| Vec3::new(x, y, z))
            .to_vec();
        let normals = vec![Vec3::Z; 4];
        let triangles = vec![0, 1, 2, 0, 2, 3];
        let edges = MeshEdges::new(&positions, &triangles);
        let facing = FacingMesh::new(positions.len(), triangles.clone(), 0);
        let inputs = TexgenInputs {
            positions: &positions,
            normals: &normals,
            triangles: &triangles,
            facing: &facing,
            edges: Some(&edges),
            origin: Vec3::ZERO,
            distant: EmGeometry::SphereAtInfinity,
            local: EmGeometry::SphereAtInfinity,
        };
        // The eye at the origin looking down -z.
        let view_proj = glam::camera::rh::proj::vulkan::perspective(1.0, 4.0 / 3.0, 0.1, 10.0);
        let request = TexgenRequest {
            eye: Vec3::ZERO,
            view_proj,
            size: (64, 48),
            settings: PemSettings {
                edge_filter,
                ..PemSettings::new(PemKind::Layered)
            },
        };
        inputs.compute(request).screen
    }

    #[test]
    fn the_outline_falls_back_to_the_whole_frame_where_no_bound_holds() {
        // In front: bands and the rim's tiles, not the whole frame.
        let front = screen_of(-3.0, true);
        assert!(!front.bands.is_empty() && !front.outline.is_empty());
        let tiled: u32 = front
            .outline
            .iter()
            .map(|r| r.extent.width * r.extent.height)
            .sum();
        assert!(tiled < 64 * 48, "{tiled} pixels of tiles");
        // Through the eye's plane: no bands, and the filter runs everywhere.
        let through = screen_of(0.5, true);
        assert!(through.bands.is_empty());
        assert_eq!(through.outline.len(), 1);
        assert_eq!(
            through.outline[0].extent.width * through.outline[0].extent.height,
            64 * 48
        );
        // Off: no tiles either way.
        assert!(screen_of(-3.0, false).outline.is_empty());
        assert!(screen_of(0.5, false).outline.is_empty());
    }
}
