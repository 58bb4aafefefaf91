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

/// A point on the lens surface as a ray meets it, normals facing the ray.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub p: Vec3,
    /// Geometric normal on the side the ray came from.
    pub ng: Vec3,
    /// Interpolated normal on the same side (the geometric one where it fails).
    pub ns: Vec3,
    /// The ray arrived on the side the winding faces (from outside the glass).
    pub front: bool,
}

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
        let m = &self.mesh;
        let t = hit.prim.triangle as usize;
        let idx = [
            m.indices[3 * t] as usize,
            m.indices[3 * t + 1] as usize,
            m.indices[3 * t + 2] as usize,
        ];
        let [a, b, c] = m.triangle(t);
        let w = [1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y];
        let p = a * w[0] + b * w[1] + c * w[2];
        let ng_wound = (b - a).cross(c - a).normalize_or(-dir);
        let front = ng_wound.dot(dir) < 0.0;
        let side = if front { 1.0 } else { -1.0 };
        let ng = ng_wound * side;
        let ns = match idx.map(|i| m.normals.get(i)) {
            [Some(&na), Some(&nb), Some(&nc)] => {
                (na * w[0] + nb * w[1] + nc * w[2]).normalize_or(ng_wound) * side
            }
            _ => ng,
        };
        let ns = if ns.dot(-dir) > 0.0 && ns.dot(ng) > 0.0 {
            ns
        } else {
            ng
        };
        Surface { p, ng, ns, front }
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
