//! Primary rays that match the engine's rasteriser pixel for pixel: the same projection
//! (`glam` right-handed Vulkan perspective, the engine's far plane) and view matrix, pixel
//! `(x, y)` with y down and its centre at `(x + ½, y + ½)`.

use glam::{DMat4, DVec4, Mat4, Vec3};

use crate::scene::Scene;

pub struct CameraRays {
    /// Clip space → world space, in f64 so the unprojection adds no visible error.
    clip_to_world: DMat4,
    width: f64,
    height: f64,
}

/// Far plane of every view: max(scene diagonal, camera far), so the whole room is inside
/// the frustum from anywhere in it.
pub fn far_plane(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds();
    (hi - lo).length().max(scene.camera.far)
}

/// The projection of a `width`×`height` frame; the engine's renderer uses this function.
pub fn projection(scene: &Scene, width: u32, height: u32) -> Mat4 {
    glam::camera::rh::proj::vulkan::perspective(
        scene.camera.fov_y_deg.to_radians(),
        width as f32 / height as f32,
        scene.camera.near,
        far_plane(scene),
    )
}

impl CameraRays {
    pub fn new(scene: &Scene, eye: Vec3, width: u32, height: u32) -> CameraRays {
        let view_proj = projection(scene, width, height) * scene.orbit.view(eye);
        CameraRays {
            clip_to_world: view_proj.as_dmat4().inverse(),
            width: f64::from(width),
            height: f64::from(height),
        }
    }

    /// Ray through film point `(px, py)` in pixels (y down): it starts on the near plane,
    /// where the rasteriser clips, and has a unit direction.
    pub fn ray(&self, px: f32, py: f32) -> (Vec3, Vec3) {
        let x = 2.0 * f64::from(px) / self.width - 1.0;
        let y = 2.0 * f64::from(py) / self.height - 1.0;
        let unproject = |z: f64| {
            let p = self.clip_to_world * DVec4::new(x, y, z, 1.0);
            p.truncate() / p.w
        };
        let near = unproject(0.0);
        let far = unproject(1.0);
        let dir = (far - near).normalize_or(glam::DVec3::NEG_Z);
        (near.as_vec3(), dir.as_vec3())
    }

    /// Film position (pixels, y down) of world point `p`, as the rasteriser would place it.
    pub fn project(&self, p: Vec3) -> (f32, f32) {
        let c = self.clip_to_world.inverse() * p.as_dvec3().extend(1.0);
        let ndc = c.truncate() / c.w;
        (
            ((ndc.x + 1.0) * 0.5 * self.width) as f32,
            ((ndc.y + 1.0) * 0.5 * self.height) as f32,
        )
    }
}
