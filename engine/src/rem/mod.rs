//! Reflection-space image-based rendering (Cabral, Olano, Nemec 1999):
//! radiance environment maps traced at the view directions of a geodesic
//! sphere around the reflector (`sources`), and per frame the spherical
//! triangle holding the view, its three maps warped into the view's
//! sphere map in reflection space and blended by spherical barycentric
//! weights (`passes::rem`), the reflector shaded from the result.

pub mod geometry;
pub mod sources;

pub use crate::passes::rem::{FADE_COS, WarpDraw};
use geometry::{Geodesic, view_frame};
use glam::{Mat3, Vec3};

/// The per-frame side of playback: which maps a view blends.
#[derive(Clone, Debug)]
pub struct RemViews {
    pub geodesic: Geodesic,
    /// The reflector's EM origin: view directions start there.
    pub origin: Vec3,
    /// Blend the three maps of the view's triangle (false: the one with
    /// the largest weight alone, still warped).
    pub blend: bool,
}

impl RemViews {
    /// The blended map's frame for `eye` and the source maps it draws.
    pub fn draws(&self, eye: Vec3) -> (Mat3, Vec<WarpDraw>) {
        let view = (eye - self.origin).normalize_or(Vec3::Z);
        let b = self.geodesic.blend(view);
        let mut draws: Vec<WarpDraw> = (0..3)
            .filter(|&i| b.weights[i] > 0.0)
            .map(|i| WarpDraw {
                frame: view_frame(self.geodesic.vertices[b.sources[i]]),
                weight: b.weights[i],
                layer: b.sources[i] as u32,
            })
            .collect();
        if !self.blend {
            draws.sort_by(|a, b| b.weight.total_cmp(&a.weight));
            draws.truncate(1);
            if let Some(d) = draws.first_mut() {
                d.weight = 1.0;
            }
        }
        (view_frame(view), draws)
    }
}

/// A reflector played by reflection-space IBR: its maps on the device
/// and the views they were traced from.
pub struct RemPlayer {
    pub gpu: crate::passes::rem::RemRenderer,
    pub views: RemViews,
    /// Bytes of the source maps on the device.
    pub bytes: u64,
    /// The reflector's world-space bounds (the `rem` pass's render area).
    pub bounds: (Vec3, Vec3),
}

impl RemPlayer {
    pub fn new(
        device: &crate::backend::Device,
        executor: &mut crate::graph::Executor,
        scene: &inference::scene::Scene,
        maps: &sources::SourceMaps,
        blend: bool,
        formats: (ash::vk::Format, ash::vk::Format),
    ) -> crate::backend::GpuResult<Self> {
        let warp = sources::RemWarp::of(scene, maps.object).unwrap_or(sources::RemWarp::Mirror);
        let parts = scene.local_group(maps.object);
        let origin = sources::group_origin(scene, &parts);
        let bounds =
            inference::scene::Mesh::bounds_of(parts.iter().map(|&o| &scene.objects[o].mesh));
        let texels = maps.upload(warp, parts);
        let gpu = crate::passes::rem::RemRenderer::new(device, executor, &texels, formats)?;
        Ok(Self {
            gpu,
            views: RemViews {
                geodesic: maps.geodesic.clone(),
                origin,
                blend,
            },
            bytes: maps.device_bytes(),
            bounds,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_on_a_vertex_draws_that_map_alone_and_between_draws_three() {
        let views = RemViews {
            geodesic: Geodesic::new(0),
            origin: Vec3::new(0.0, 0.5, 0.0),
            blend: true,
        };
        let v = views.geodesic.vertices[4];
        let (frame, draws) = views.draws(views.origin + 3.0 * v);
        assert_eq!(draws.len(), 1, "{draws:?}");
        assert_eq!(draws[0].layer, 4);
        assert!((draws[0].frame.col(2) - frame.col(2)).length() < 1e-5);
        let between = (views.geodesic.vertices[4] + 0.3 * views.geodesic.vertices[5]).normalize();
        let (_, draws) = views.draws(views.origin + between);
        let total: f32 = draws.iter().map(|d| d.weight).sum();
        assert!((total - 1.0).abs() < 1e-5 && draws.len() >= 2, "{draws:?}");
        let nearest = RemViews {
            blend: false,
            ..views
        };
        let (_, one) = nearest.draws(nearest.origin + between);
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].weight, 1.0);
    }
}
