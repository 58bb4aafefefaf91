//! The local lens object (thesis §6): one glass object in its own BVH, so
//! vertex rays touch only its triangles, with the surface a hit lands on
//! computed exactly as the tracer computes it (same normals, same sides).

use glam::{Vec2, Vec3};

use crate::scene::{Material, Mesh, Scene};
use crate::trace::SceneBvh;
use crate::trace::bvh::Hit;

/// Interfaces a greedy path may cross, the first included: the tracer's
/// default specular bounce limit, so both drop the same long paths.
pub const DEFAULT_MAX_INTERFACES: u32 = 8;

/// A glass object ready for vertex ray tracing.
pub struct Lens {
    /// Index of the object in its scene (its hits report it).
    pub object: u32,
    pub mesh: Mesh,
    pub ior: f32,
    /// Beer–Lambert absorption per metre and channel.
    pub absorption: Vec3,
    /// Interfaces a path may cross before it counts as never exiting.
    pub max_interfaces: u32,
    bvh: SceneBvh,
}

/// A point on the lens surface as a ray meets it, normals facing the ray:
/// the tracer's own type and rules.
pub use crate::trace::surface::Surface;

#[derive(Debug, thiserror::Error)]
pub enum LensError {
    #[error("scene {scene}: no object named {name:?}")]
    NoObject { scene: String, name: String },
    #[error("scene {scene}: object {name:?} is not glass (expected material kind \"glass\")")]
    NotGlass { scene: String, name: String },
}

impl Lens {
    /// The glass object `name` of `scene`, with the tracer's bounce limit.
    pub fn new(scene: &Scene, name: &str) -> Result<Lens, LensError> {
        let Some(index) = scene.objects.iter().position(|o| o.name == name) else {
            return Err(LensError::NoObject {
                scene: scene.name.clone(),
                name: name.into(),
            });
        };
        let object = &scene.objects[index];
        let Some(&Material::Glass { ior, absorption }) = scene.materials.get(object.material)
        else {
            return Err(LensError::NotGlass {
                scene: scene.name.clone(),
                name: name.into(),
            });
        };
        Ok(Lens::from_mesh(
            index as u32,
            object.mesh.clone(),
            ior,
            absorption,
        ))
    }

    /// A lens from a bare mesh (tests, tools).
    pub fn from_mesh(object: u32, mesh: Mesh, ior: f32, absorption: Vec3) -> Lens {
        let bvh = SceneBvh::from_meshes(&[(object, &mesh)]);
        Lens {
            object,
            mesh,
            ior,
            absorption,
            max_interfaces: DEFAULT_MAX_INTERFACES,
            bvh,
        }
    }

    /// Nearest lens hit along a ray, `t ≥ 0`.
    pub fn closest(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        self.bvh.closest(origin, dir, 0.0, f32::INFINITY, None)
    }

    /// The surface at `hit` (a hit on this lens: from [`Lens::closest`] or
    /// from the scene's BVH) for a ray along `dir` — the tracer's rules.
    pub fn surface(&self, hit: &Hit, dir: Vec3) -> Surface {
        Surface::at(&self.mesh, hit.prim.triangle as usize, hit.bary, dir)
    }

    /// The surface at a mesh vertex seen along `dir`: its normal stands for
    /// both normals (a vertex has no face), turned towards the ray.
    pub fn vertex_surface(p: Vec3, normal: Vec3, dir: Vec3) -> Surface {
        let n = normal.try_normalize().unwrap_or(-dir);
        let front = n.dot(dir) < 0.0;
        let n = if front { n } else { -n };
        Surface {
            p,
            ng: n,
            ns: n,
            uv: Vec2::ZERO,
            front,
        }
    }

    /// Triangles of the lens (for sizes and reports).
    pub fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }
}

/// The hit at barycentrics `bary` of triangle `triangle` (tests and tools).
pub fn hit_on(object: u32, triangle: u32, bary: Vec2, t: f32) -> Hit {
    Hit {
        t,
        prim: crate::trace::bvh::PrimRef { object, triangle },
        bary,
    }
}
