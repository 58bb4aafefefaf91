//! Frames in flight for glass: the next frame's vertex ray paths, traced on
//! a worker while the device renders this frame. A hybrid frame is mostly
//! CPU ray paths and lavapipe keeps only part of the two cores busy while
//! it renders, so the paths of frame N + 1 fill the cores frame N leaves
//! idle. The result is used only for exactly the view it was asked for.

use std::sync::Arc;
use std::thread::JoinHandle;

use glam::{Mat4, Vec3};
use inference::glass::baseline::baseline_mesh;
use inference::glass::{Lens, Screen, TessSettings, Tessellation, tessellate};

use super::GlassKind;

/// What one frame's glass geometry depends on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathRequest {
    pub kind: GlassKind,
    pub eye: Vec3,
    pub view_proj: Mat4,
    pub size: (u32, u32),
    /// Tessellation threshold, subpixels (hybrid frames).
    pub tau: f32,
}

/// The lens's geometry for `request`: adaptive tessellation with both
/// greedy paths at every vertex (hybrid), or the lens's own mesh with one
/// refraction (the static refraction EM baseline).
pub fn trace(lens: &Lens, request: &PathRequest) -> Tessellation {
    match request.kind {
        GlassKind::Hybrid => {
            let screen = Screen {
                view_proj: request.view_proj,
                width: request.size.0,
                height: request.size.1,
            };
            tessellate(lens, request.eye, screen, TessSettings::new(request.tau))
        }
        GlassKind::StaticEm => baseline_mesh(lens, request.eye),
    }
}

/// A trace running on its own thread (its rays on rayon's pool).
pub struct Ahead {
    request: PathRequest,
    handle: JoinHandle<Tessellation>,
}

impl Ahead {
    /// Starts tracing `request`; `None` when no thread could be started
    /// (the frame then traces in line, as without frames in flight).
    pub fn start(lens: Arc<Lens>, request: PathRequest) -> Option<Ahead> {
        let handle = std::thread::Builder::new()
            .name("glass paths ahead".into())
            .spawn(move || trace(&lens, &request))
            .ok()?;
        Some(Ahead { request, handle })
    }

    /// Waits for the worker and drops what it traced (the view it was
    /// traced for will not be drawn).
    pub fn finish(self) {
        let _ = self.handle.join();
    }

    /// The traced geometry if it was asked for `request`; otherwise (a view
    /// the playback did not predict) waits for the worker and drops it.
    pub fn take(self, request: &PathRequest) -> Option<Tessellation> {
        let traced = self.handle.join().ok()?;
        (self.request == *request).then_some(traced)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use inference::scene::Scene;

    fn request(scene: &Scene, azimuth: f32) -> PathRequest {
        let eye = scene.orbit.eye(azimuth, 0.0);
        let size = (64, 48);
        let projection = inference::trace::camera::projection(scene, size.0, size.1);
        PathRequest {
            kind: GlassKind::Hybrid,
            eye,
            view_proj: projection * scene.orbit.view(eye),
            size,
            tau: 30.0,
        }
    }

    #[test]
    fn ahead_gives_the_same_geometry_for_its_view_and_none_for_another() {
        let scene = Scene::load("glass").expect("built-in glass scene");
        let lens = Arc::new(Lens::new(&scene, "teapot").expect("glass teapot"));
        let here = request(&scene, 10.0);
        let inline = trace(&lens, &here);
        let ahead = Ahead::start(lens.clone(), here).expect("a thread");
        let traced = ahead.take(&here).expect("the view it was asked for");
        assert_eq!(traced.positions, inline.positions);
        assert_eq!(traced.indices, inline.indices);
        assert_eq!(traced.paths, inline.paths);
        let there = request(&scene, 11.0);
        let ahead = Ahead::start(lens, here).expect("a thread");
        assert!(ahead.take(&there).is_none(), "another view is traced anew");
        let other_tau = PathRequest { tau: 10.0, ..here };
        assert_ne!(here, other_tau);
    }
}
