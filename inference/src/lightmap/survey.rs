//! Where a set of views sees each diffuse object, and how finely: one ray
//! per `stride`-th pixel of every view (the rasteriser's own projection and
//! pixel centres), and at each hit the chart→screen Jacobian's largest
//! singular value in pixels per metre — the quantity the thesis's
//! resolution rule bounds (papers.md §1: texture→screen Jacobian ≤ 1.25).

use super::charts::{Charts, charts};
use crate::scene::{Material, Scene};
use crate::trace::bvh::SceneBvh;
use crate::trace::camera::{CameraRays, projection};
use glam::{DMat4, DVec3, Vec2, Vec3};
use rayon::prelude::*;

/// What the views see of one chart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChartSight {
    /// Bounds of the seen chart coordinates (metres).
    pub lo: Vec2,
    pub hi: Vec2,
    /// Largest chart→screen magnification seen, pixels per metre.
    pub pixels_per_metre: f32,
    /// Rays that hit the chart.
    pub hits: u32,
}

impl ChartSight {
    fn at(c: Vec2, pixels_per_metre: f32) -> Self {
        Self {
            lo: c,
            hi: c,
            pixels_per_metre,
            hits: 1,
        }
    }

    fn merge(self, o: Self) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            pixels_per_metre: self.pixels_per_metre.max(o.pixels_per_metre),
            hits: self.hits + o.hits,
        }
    }
}

/// One diffuse object: its charts and what the views see of each (None:
/// no ray reached that chart).
#[derive(Clone, Debug)]
pub struct ObjectSight {
    /// Index in `scene.objects`.
    pub object: usize,
    pub charts: Charts,
    pub sights: Vec<Option<ChartSight>>,
}

impl ObjectSight {
    pub fn seen(&self) -> bool {
        self.sights.iter().any(Option::is_some)
    }
}

/// Whether `scene.objects[object]` is Lambertian: what gets a light map.
pub fn is_diffuse(scene: &Scene, object: usize) -> bool {
    scene
        .objects
        .get(object)
        .and_then(|o| scene.materials.get(o.material))
        .is_some_and(|m| matches!(m, Material::Diffuse { .. }))
}

/// Per-object, per-chart sights; merged over rows and views.
type Tally = Vec<Vec<Option<ChartSight>>>;

fn merge_tallies(mut a: Tally, b: Tally) -> Tally {
    for (x, y) in a.iter_mut().zip(b) {
        for (s, t) in x.iter_mut().zip(y) {
            *s = match (*s, t) {
                (Some(s), Some(t)) => Some(s.merge(t)),
                (s, t) => s.or(t),
            };
        }
    }
    a
}

/// Every diffuse object of `scene` (scene order) with what `eyes` see of
/// it in `width × height` frames, one ray per `stride`-th pixel in x and y.
/// Deterministic: merges are order-independent (min, max, sums).
pub fn survey(
    scene: &Scene,
    bvh: &SceneBvh,
    eyes: &[Vec3],
    (width, height): (u32, u32),
    stride: u32,
) -> Vec<ObjectSight> {
    let diffuse: Vec<usize> = (0..scene.objects.len())
        .filter(|&o| is_diffuse(scene, o))
        .collect();
    let charted: Vec<Charts> = diffuse
        .iter()
        .map(|&o| charts(&scene.objects[o].mesh))
        .collect();
    let slot = |object: usize| diffuse.iter().position(|&o| o == object);
    let empty: Tally = charted.iter().map(|c| vec![None; c.count()]).collect();
    let stride = stride.max(1);
    let rows: Vec<(usize, u32)> = (0..eyes.len())
        .flat_map(|e| (0..height).step_by(stride as usize).map(move |y| (e, y)))
        .collect();
    let cameras: Vec<(CameraRays, DMat4)> = eyes
        .iter()
        .map(|&eye| {
            let m = projection(scene, width, height) * scene.orbit.view(eye);
            (CameraRays::new(scene, eye, width, height), m.as_dmat4())
        })
        .collect();
    let screen = Screen {
        width: f64::from(width),
        height: f64::from(height),
    };
    let tally = rows
        .par_iter()
        .map(|&(e, y)| {
            let mut tally = empty.clone();
            let (rays, view_proj) = &cameras[e];
            for x in (0..width).step_by(stride as usize) {
                let (origin, dir) = rays.ray(x as f32 + 0.5, y as f32 + 0.5);
                let Some(hit) = bvh.closest(origin, dir, 0.0, f32::INFINITY, None) else {
                    continue;
                };
                let object = hit.prim.object as usize;
                let Some(k) = slot(object) else { continue };
                let mesh = &scene.objects[object].mesh;
                let t = hit.prim.triangle as usize;
                let [a, b, c] = mesh.triangle(t);
                if (b - a).cross(c - a).dot(dir) >= 0.0 {
                    continue; // a back face: the rasteriser culls it
                }
                let chart = &charted[k];
                let Some((t_u, t_v)) = chart.tangents(mesh, t) else {
                    continue;
                };
                let i = &mesh.indices[3 * t..3 * t + 3];
                let w = [1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y];
                let coords = (0..3).fold(Vec2::ZERO, |s, j| s + chart.coords[i[j] as usize] * w[j]);
                let p = origin + dir * hit.t;
                let ppm = screen.magnification(view_proj, p, t_u, t_v);
                let id = chart.triangle_chart(mesh, t) as usize;
                let s = &mut tally[k][id];
                let here = ChartSight::at(coords, ppm);
                *s = Some(s.map_or(here, |s| s.merge(here)));
            }
            tally
        })
        .reduce(|| empty.clone(), merge_tallies);
    diffuse
        .into_iter()
        .zip(charted)
        .zip(tally)
        .map(|((object, charts), sights)| ObjectSight {
            object,
            charts,
            sights,
        })
        .collect()
}

struct Screen {
    width: f64,
    height: f64,
}

impl Screen {
    fn pixel(&self, view_proj: &DMat4, p: DVec3) -> Option<(f64, f64)> {
        let c = *view_proj * p.extend(1.0);
        (c.w > 1e-9).then(|| {
            (
                (c.x / c.w + 1.0) * 0.5 * self.width,
                (c.y / c.w + 1.0) * 0.5 * self.height,
            )
        })
    }

    /// Largest singular value of d(screen)/d(chart) at `p`, pixels per
    /// metre (central differences over ±1 mm along the chart's axes).
    fn magnification(&self, view_proj: &DMat4, p: Vec3, t_u: Vec3, t_v: Vec3) -> f32 {
        const H: f64 = 1e-3;
        let p = p.as_dvec3();
        let d = |t: Vec3| -> Option<(f64, f64)> {
            let t = t.as_dvec3() * H;
            let (a, b) = (self.pixel(view_proj, p + t)?, self.pixel(view_proj, p - t)?);
            Some(((a.0 - b.0) / (2.0 * H), (a.1 - b.1) / (2.0 * H)))
        };
        let (Some((a, c)), Some((b, dd))) = (d(t_u), d(t_v)) else {
            return 0.0;
        };
        let s = a * a + b * b + c * c + dd * dd;
        let det = a * dd - b * c;
        (0.5 * (s + (s * s - 4.0 * det * det).max(0.0).sqrt()))
            .sqrt()
            .min(f64::from(f32::MAX)) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_teapot_room_floor_is_seen_near_and_the_ceiling_not_from_the_orbit() {
        let scene = Scene::load("teapot").expect("teapot");
        let bvh = SceneBvh::build(&scene);
        let eyes = [scene.orbit.eye(0.0, 0.0), scene.orbit.eye(99.0, 0.0)];
        let sights = survey(&scene, &bvh, &eyes, (160, 120), 2);
        let named = |n: &str| {
            sights
                .iter()
                .find(|s| scene.objects[s.object].name == n)
                .expect(n)
        };
        let floor = named("floor");
        let s = floor.sights[0].expect("the floor is seen");
        // 160 px over 2·atan(4/3·tan 20°) ≈ 0.89 rad: ≈ 180 px/rad, ≈ 1.2 m away
        // at the bottom edge of the frame, so well over 100 px per metre.
        assert!(
            s.pixels_per_metre > 100.0 && s.pixels_per_metre < 1000.0,
            "{s:?}"
        );
        assert!(s.hits > 1000);
        assert!(!named("ceiling").seen(), "the orbit looks down");
        let walls = named("walls");
        assert_eq!(walls.sights.len(), 4);
        // The walls behind the orbit (+x and +z) are never in view.
        assert_eq!(walls.sights.iter().filter(|s| s.is_some()).count(), 2);
    }

    #[test]
    fn magnification_of_a_fronto_parallel_plane_is_the_focal_length_over_distance() {
        let scene = Scene::load("teapot").expect("teapot");
        let eye = scene.orbit.eye(0.0, 0.0);
        let view_proj = (projection(&scene, 640, 480) * scene.orbit.view(eye)).as_dmat4();
        let screen = Screen {
            width: 640.0,
            height: 480.0,
        };
        let dir = (scene.orbit.center - eye).normalize();
        let right = dir.cross(Vec3::Y).normalize();
        let up = right.cross(dir);
        let p = eye + dir * 2.0;
        let focal = 240.0 / (scene.camera.fov_y_deg.to_radians() * 0.5).tan();
        let got = screen.magnification(&view_proj, p, right, up);
        assert!(
            (f64::from(got) - f64::from(focal) / 2.0).abs() < 0.01,
            "{got} vs {focal}/2"
        );
    }
}
