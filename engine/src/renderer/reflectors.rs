//! The scene's reflective objects as static-EM frames draw them: each with
//! its own cube map (captured once at set-up) and the world-space vertices
//! that CPU texgen reads every frame.

use super::{COLOR_FORMAT, DEFAULT_EM_RESOLUTION};
use crate::backend::{Device, GpuResult};
use crate::passes::em_capture::CubeTarget;
use crate::passes::mirror::{MirrorDraw, MirrorRenderer};
use glam::Vec3;
use inference::scene::{Material, Scene};

/// A reflective object and the static environment map it samples.
pub(super) struct Reflector {
    pub(super) draw: MirrorDraw,
    pub(super) cube: CubeTarget,
    /// World-space vertices, the input of CPU texgen every frame.
    pub(super) positions: Vec<Vec3>,
    pub(super) normals: Vec<Vec3>,
    /// World-space bounds, for the mirror pass's render area.
    pub(super) bounds: (Vec3, Vec3),
}

/// One `Reflector` per mirror or glossy object of `scene` (scene order),
/// its cube sized by the object's `[em]` settings.
pub(super) fn static_em_reflectors(
    device: &Device,
    scene: &Scene,
    mirror: &MirrorRenderer,
) -> GpuResult<Vec<Reflector>> {
    let mut reflectors = Vec::new();
    for (index, object) in scene.objects.iter().enumerate() {
        let f0 = match scene.materials.get(object.material) {
            Some(Material::Mirror { f0 }) | Some(Material::Glossy { f0, .. }) => *f0,
            _ => continue,
        };
        let size = object
            .em
            .as_ref()
            .map_or(DEFAULT_EM_RESOLUTION, |em| em.resolution);
        let cube = CubeTarget::new(
            device,
            &format!("{} static EM", object.name),
            size,
            COLOR_FORMAT,
            object.mesh.area_weighted_centroid(),
        )?;
        let draw = mirror.draw_for(index, object.mesh.positions.len(), f0, &cube.color)?;
        reflectors.push(Reflector {
            draw,
            cube,
            positions: object.mesh.positions.clone(),
            normals: object.mesh.normals.clone(),
            bounds: object.mesh.bounds(),
        });
    }
    Ok(reflectors)
}
