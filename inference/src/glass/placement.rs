//! The shells of a scene's lens (thesis §6.3.2): exit-ray hits of views
//! spread over the whole viewpoint space, clustered together, so the
//! layers agree from sample to sample. Coarse views suffice: the
//! clustering reads hit distances, not pixels.

use glam::Vec3;

use super::cluster::{ClusterInput, place_shells};
use super::lens::Lens;
use super::records::exit_ray_hits;
use super::shells::{MAX_SHELLS, ShellSet};
use super::tessellate::{Screen, TessSettings, tessellate};
use super::{room_box, room_objects};
use crate::scene::Scene;
use crate::trace::SceneBvh;

/// Azimuth lines of the orbit whose views are clustered, at most.
const VIEW_LINES: u32 = 8;
/// The clustering views' size and tessellation threshold (subpixels).
const VIEW_SIZE: (u32, u32) = (160, 120);
const VIEW_TAU: f32 = 30.0;

/// The eyes the shells are placed from: up to [`VIEW_LINES`] azimuth lines
/// spread over the orbit (both ends included), on every ring.
pub fn placement_eyes(scene: &Scene) -> Vec<Vec3> {
    let orbit = &scene.orbit;
    let lines = orbit.samples.max(1);
    let n = lines.min(VIEW_LINES);
    let picks: Vec<u32> = (0..n)
        .map(|i| match n {
            1 => 0,
            _ => (i * (lines - 1) + (n - 1) / 2) / (n - 1),
        })
        .collect();
    orbit
        .ring_elevations()
        .into_iter()
        .flat_map(|e| picks.iter().map(move |&l| orbit.eye(orbit.angle_deg(l), e)))
        .collect()
}

/// The shells of `lens` in `scene`, at most `max_shells` (1 to
/// [`MAX_SHELLS`]): LBG over the exit-ray hits of [`placement_eyes`],
/// whole objects to one cluster. A lens alone in the room gets the room's
/// box alone.
pub fn place_for_scene(scene: &Scene, lens: &Lens, max_shells: usize) -> ShellSet {
    let bvh = SceneBvh::build(scene);
    let (width, height) = VIEW_SIZE;
    let proj = crate::trace::camera::projection(scene, width, height);
    let mut rays = Vec::new();
    for eye in placement_eyes(scene) {
        let screen = Screen {
            view_proj: proj * scene.orbit.view(eye),
            width,
            height,
        };
        let tess = tessellate(lens, eye, screen, TessSettings::new(VIEW_TAU));
        rays.extend(exit_ray_hits(scene, &bvh, lens, &tess));
    }
    let room = room_objects(scene);
    place_shells(&ClusterInput {
        origin: lens.mesh.area_weighted_centroid(),
        rays: &rays,
        room_objects: &room,
        room_box: room_box(scene),
        max_shells: max_shells.clamp(1, MAX_SHELLS),
    })
}
