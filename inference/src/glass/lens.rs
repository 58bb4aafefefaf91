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
    /// Per triangle, its plane when it lies on the lens's convex hull
    /// (unit outward normal n, n·a): a ray on the plane's outer side going
    /// outwards cannot meet the lens again (see [`Lens::escapes`]).
    hull_planes: Vec<Option<(Vec3, f32)>>,
    /// How far in front of a hull plane a ray must start to escape: twice
    /// the hull test's tolerance (a vertex may lie that far in front).
    escape_margin: f32,
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
        let (hull_planes, escape_margin) = hull_planes(&mesh);
        Lens {
            object,
            mesh,
            ior,
            absorption,
            max_interfaces: DEFAULT_MAX_INTERFACES,
            bvh,
            hull_planes,
            escape_margin,
        }
    }

    /// True when lens triangle `triangle` lies on the convex hull.
    pub fn on_hull(&self, triangle: u32) -> bool {
        matches!(self.hull_planes.get(triangle as usize), Some(Some(_)))
    }

    /// True when the ray from `origin` along `dir`, leaving triangle
    /// `triangle`, cannot meet the lens: the triangle lies on the convex
    /// hull, the ray starts in front of its plane by more than the hull
    /// test's slack and moves away from it, so every point of the ray lies
    /// where no vertex (and so no triangle) of the lens does. Such rays —
    /// most exits through the outer side of a convex part — need no
    /// traversal; the answer is the traversal's (a miss) either way.
    pub fn escapes(&self, triangle: u32, origin: Vec3, dir: Vec3) -> bool {
        let Some(Some((n, d))) = self.hull_planes.get(triangle as usize) else {
            return false;
        };
        n.dot(dir) > 0.0 && n.dot(origin) - d > self.escape_margin
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

/// The hull planes of `mesh`'s triangles and the margin a ray must keep in
/// front of them (see [`Lens::escapes`]).
fn hull_planes(mesh: &Mesh) -> (Vec<Option<(Vec3, f32)>>, f32) {
    let on_hull = crate::hull::hull_triangles(mesh);
    let planes = (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            let n = (b - a).cross(c - a).try_normalize()?;
            on_hull
                .get(t)
                .copied()
                .unwrap_or(false)
                .then(|| (n, n.dot(a)))
        })
        .collect();
    // The hull test's tolerance (`inference::hull`), doubled, plus the
    // rounding of n·origin in f32 at the mesh's magnitude.
    let (lo, hi) = mesh.positions.iter().filter(|p| p.is_finite()).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let diagonal = (hi - lo).length();
    let magnitude = lo.abs().max(hi.abs()).max_element().max(1.0);
    let tolerance =
        crate::hull::RELATIVE_TOLERANCE as f32 * diagonal + 8.0 * f32::EPSILON * magnitude;
    let margin = 2.0 * tolerance + 4.0 * f32::EPSILON * magnitude;
    (
        planes,
        if margin.is_finite() {
            margin
        } else {
            f32::INFINITY
        },
    )
}
