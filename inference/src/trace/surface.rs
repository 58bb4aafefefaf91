//! Where a ray meets a mesh triangle, as the tracer sees it: the point,
//! the geometric and interpolated normals turned towards the ray, the UV
//! and the side hit. The glass's vertex paths use the same function, so the
//! hybrid lens and the gold standard meet the same surfaces.

use glam::{Vec2, Vec3};

use crate::scene::Mesh;

/// A hit point, normals facing the incoming ray.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub p: Vec3,
    /// Geometric normal on the side the ray came from.
    pub ng: Vec3,
    /// Interpolated normal on the same side (the geometric one where
    /// interpolation fails or would face away from the ray).
    pub ns: Vec3,
    pub uv: Vec2,
    /// The ray hit the side the triangle winding faces.
    pub front: bool,
}

impl Surface {
    /// The surface of `mesh`'s triangle `t` at barycentrics `bary`
    /// (`(b1, b2)`, as hits report them) for a ray travelling along `dir`.
    pub fn at(mesh: &Mesh, t: usize, bary: Vec2, dir: Vec3) -> Surface {
        let idx = [
            mesh.indices[3 * t] as usize,
            mesh.indices[3 * t + 1] as usize,
            mesh.indices[3 * t + 2] as usize,
        ];
        let [a, b, c] = mesh.triangle(t);
        let w = [1.0 - bary.x - bary.y, bary.x, bary.y];
        let p = a * w[0] + b * w[1] + c * w[2];
        let ng_wound = (b - a).cross(c - a).normalize_or(-dir);
        let front = ng_wound.dot(dir) < 0.0;
        let side = if front { 1.0 } else { -1.0 };
        let ng = ng_wound * side;
        let ns = match idx.map(|i| mesh.normals.get(i)) {
            [Some(&na), Some(&nb), Some(&nc)] => {
                (na * w[0] + nb * w[1] + nc * w[2]).normalize_or(ng_wound) * side
            }
            _ => ng,
        };
        // An interpolated normal facing away from the viewer would reflect into the surface.
        let ns = if ns.dot(-dir) > 0.0 && ns.dot(ng) > 0.0 {
            ns
        } else {
            ng
        };
        let uv = match idx.map(|i| mesh.uvs.get(i)) {
            [Some(&ua), Some(&ub), Some(&uc)] => ua * w[0] + ub * w[1] + uc * w[2],
            _ => Vec2::ZERO,
        };
        Surface {
            p,
            ng,
            ns,
            uv,
            front,
        }
    }
}
