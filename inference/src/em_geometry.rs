//! Environment-map geometry (PEM paper §3–4): the reflected ray from each
//! vertex is intersected with the EM's geometry and `hit − EM origin` is the
//! cube lookup. A sphere at infinity makes the lookup the direction itself;
//! a finite box (distant layer) or axis-aligned ellipsoid (local layer)
//! gives the parallax a static EM lacks.
//!
//! Every function returns finite values for every finite input: a ray that
//! misses (it starts outside the shape and points away, or grazes it) falls
//! back to its direction, i.e. to the sphere at infinity.

use crate::texgen::reflect_view;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EmGeometry {
    SphereAtInfinity,
    /// Axis-aligned box (the room for the distant layer).
    Box {
        min: Vec3,
        max: Vec3,
    },
    /// Axis-aligned ellipsoid (the local layer around the reflector).
    Ellipsoid {
        center: Vec3,
        radii: Vec3,
    },
}

impl EmGeometry {
    /// Distance along the unit direction `d` from `p` to where the ray
    /// leaves the shape (or first enters it from outside); `None` on a miss.
    pub fn hit_distance(&self, p: Vec3A, d: Vec3A) -> Option<f32> {
        match *self {
            EmGeometry::SphereAtInfinity => None,
            EmGeometry::Box { min, max } => {
                // Slab test; 1/0 = ±inf handles rays parallel to a face.
                let inv = d.recip();
                let t0 = (Vec3A::from(min) - p) * inv;
                let t1 = (Vec3A::from(max) - p) * inv;
                let near = t0.min(t1).max_element();
                let far = t0.max(t1).min_element();
                if far.is_nan() || far < near.max(0.0) || !far.is_finite() {
                    return None;
                }
                Some(if near > 0.0 { near } else { far })
            }
            EmGeometry::Ellipsoid { center, radii } => {
                // In the space where the ellipsoid is the unit sphere.
                let r = Vec3A::from(radii).max(Vec3A::splat(1e-12));
                let q = (p - Vec3A::from(center)) / r;
                let e = d / r;
                let a = e.length_squared();
                let b = q.dot(e);
                let c = q.length_squared() - 1.0;
                let disc = b * b - a * c;
                if disc.is_nan() || disc < 0.0 || a == 0.0 {
                    return None;
                }
                let root = disc.sqrt();
                let (t_near, t_far) = ((-b - root) / a, (-b + root) / a);
                let t = if c < 0.0 {
                    t_far
                } else if t_near > 0.0 {
                    t_near
                } else {
                    return None;
                };
                (t.is_finite() && t >= 0.0).then_some(t)
            }
        }
    }

    /// The cube lookup for a ray from `p` along unit `d`: `hit − origin`, or
    /// `d` itself where the shape is at infinity or missed.
    pub fn lookup(&self, origin: Vec3A, p: Vec3A, d: Vec3A) -> Vec3A {
        match self.hit_distance(p, d) {
            Some(t) => {
                let v = p + d * t - origin;
                // A hit exactly at the origin has no direction.
                if v.length_squared() > 1e-20 { v } else { d }
            }
            None => d,
        }
    }
}

/// Texgen against finite EM geometry: per vertex `[lookup, cos θ]`, the
/// layout the mirror pipeline reads (see `texgen::sphere_at_infinity`).
pub fn texgen(
    geometry: &EmGeometry,
    origin: Vec3,
    eye: Vec3,
    positions: &[Vec3],
    normals: &[Vec3],
    out: &mut [[f32; 4]],
) {
    let (eye, origin) = (Vec3A::from(eye), Vec3A::from(origin));
    for ((p, n), o) in positions.iter().zip(normals).zip(out.iter_mut()) {
        *o = texgen_vertex(geometry, origin, eye, *p, *n);
    }
}

/// [`texgen`] of the vertices whose `used` flag is set; the others' `out`
/// entries are left as they are (a view that draws only some triangles
/// reads only their vertices).
pub fn texgen_where(
    geometry: &EmGeometry,
    (origin, eye): (Vec3, Vec3),
    (positions, normals): (&[Vec3], &[Vec3]),
    used: &[bool],
    out: &mut [[f32; 4]],
) {
    let (eye, origin) = (Vec3A::from(eye), Vec3A::from(origin));
    let vertices = positions.iter().zip(normals).zip(used);
    for (((p, n), _), o) in vertices.zip(out.iter_mut()).filter(|(((_, _), u), _)| **u) {
        *o = texgen_vertex(geometry, origin, eye, *p, *n);
    }
}

#[inline(always)]
fn texgen_vertex(geometry: &EmGeometry, origin: Vec3A, eye: Vec3A, p: Vec3, n: Vec3) -> [f32; 4] {
    let p = Vec3A::from(p);
    let view = (p - eye).try_normalize().unwrap_or(Vec3A::NEG_Z);
    let (r, cos) = reflect_view(view, Vec3A::from(n));
    let l = geometry.lookup(origin, p, r);
    [l.x, l.y, l.z, cos]
}

/// The smallest axis-aligned ellipsoid centred at `center` containing every
/// point, by brute force over axis ratios (PEM paper: "axes chosen by brute
/// force for minimum volume"): for ratios (1, ry, rz) the needed scale is
/// s = max √(dx² + (dy/ry)² + (dz/rz)²), volume ∝ s³·ry·rz. A log grid,
/// then a finer grid around the best cell.
pub fn bounding_ellipsoid(center: Vec3, points: &[Vec3]) -> Vec3 {
    let d: Vec<Vec3A> = points.iter().map(|p| Vec3A::from(*p - center)).collect();
    if d.is_empty() {
        return Vec3::ZERO;
    }
    let cost = |ry: f32, rz: f32| {
        let inv = Vec3A::new(1.0, 1.0 / ry, 1.0 / rz);
        let s2 = d
            .iter()
            .map(|v| (*v * inv).length_squared())
            .fold(0.0f32, f32::max);
        (s2.sqrt().powi(3) * ry * rz, s2.sqrt())
    };
    let (mut best_ly, mut best_lz, mut span) = (0.0f32, 0.0f32, 3.0f32);
    for _ in 0..3 {
        let steps = 16;
        // Each grid point's volume on any thread (each is the same
        // sequential sum), then the first smallest in scan order: the
        // same radii as one thread finds, on every machine.
        let grid: Vec<(f32, f32)> = (0..=steps)
            .flat_map(|i| (0..=steps).map(move |j| (i, j)))
            .map(|(i, j)| {
                let ly = best_ly + span * (2.0 * i as f32 / steps as f32 - 1.0);
                let lz = best_lz + span * (2.0 * j as f32 / steps as f32 - 1.0);
                (ly, lz)
            })
            .collect();
        let volumes: Vec<f32> = grid
            .par_iter()
            .map(|&(ly, lz)| cost(ly.exp(), lz.exp()).0)
            .collect();
        let (mut best, mut by, mut bz) = (f32::INFINITY, best_ly, best_lz);
        for (&(ly, lz), &volume) in grid.iter().zip(&volumes) {
            if volume < best {
                (best, by, bz) = (volume, ly, lz);
            }
        }
        (best_ly, best_lz) = (by, bz);
        span /= steps as f32 / 4.0;
    }
    let (ry, rz) = (best_ly.exp(), best_lz.exp());
    let (_, s) = cost(ry, rz);
    // A hair larger so every point is strictly inside despite rounding.
    Vec3::new(s, s * ry, s * rz) * (1.0 + 1e-5)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROOM: EmGeometry = EmGeometry::Box {
        min: Vec3::new(-4.0, 0.0, -4.0),
        max: Vec3::new(4.0, 4.0, 4.0),
    };

    #[test]
    fn box_hit_from_inside_lands_on_the_wall() {
        let t = ROOM
            .hit_distance(Vec3A::new(0.0, 1.0, 0.0), Vec3A::X)
            .expect("hit");
        assert!((t - 4.0).abs() < 1e-6);
        let l = ROOM.lookup(
            Vec3A::new(0.0, 1.0, 0.0),
            Vec3A::new(1.0, 1.0, 0.0),
            Vec3A::NEG_Y,
        );
        assert!((l - Vec3A::new(1.0, -1.0, 0.0)).length() < 1e-6, "{l}");
    }

    #[test]
    fn ray_parallel_to_box_faces_and_along_an_edge_is_finite() {
        for d in [
            Vec3A::X,
            Vec3A::NEG_Z,
            Vec3A::new(1.0, 0.0, 1.0).normalize(),
        ] {
            // Starting on the floor plane, moving parallel to it.
            let l = ROOM.lookup(Vec3A::ZERO, Vec3A::new(0.0, 0.0, 0.0), d);
            assert!(l.is_finite(), "{d} -> {l}");
        }
    }

    #[test]
    fn eye_outside_the_box_falls_back_or_enters() {
        let outside = Vec3A::new(10.0, 1.0, 0.0);
        // Pointing away: a miss, the direction itself.
        assert_eq!(ROOM.lookup(Vec3A::ZERO, outside, Vec3A::X), Vec3A::X);
        // Pointing at the room: enters at the +x wall.
        let t = ROOM.hit_distance(outside, Vec3A::NEG_X).expect("enters");
        assert!((t - 6.0).abs() < 1e-5);
    }

    #[test]
    fn ellipsoid_hit_tangent_and_inside() {
        let e = EmGeometry::Ellipsoid {
            center: Vec3::ZERO,
            radii: Vec3::new(2.0, 1.0, 1.0),
        };
        let t = e.hit_distance(Vec3A::ZERO, Vec3A::X).expect("exit");
        assert!((t - 2.0).abs() < 1e-6);
        // Tangent to the top: grazes at one point or misses, never NaN.
        let l = e.lookup(Vec3A::ZERO, Vec3A::new(-5.0, 1.0, 0.0), Vec3A::X);
        assert!(l.is_finite());
        // From outside towards it: the first hit.
        let t = e
            .hit_distance(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X)
            .expect("hit");
        assert!((t - 3.0).abs() < 1e-5);
        // Eye inside the ellipsoid looking anywhere: always exits.
        for d in [
            Vec3A::Y,
            Vec3A::NEG_Z,
            Vec3A::new(1.0, 1.0, 1.0).normalize(),
        ] {
            assert!(e.hit_distance(Vec3A::new(0.5, 0.1, 0.0), d).is_some());
        }
    }

    #[test]
    fn texgen_is_finite_at_extremes() {
        let mut out = [[0.0; 4]; 3];
        let positions = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(4.0, 4.0, 4.0),
            Vec3::ONE,
        ];
        let normals = [Vec3::Y, Vec3::ZERO, Vec3::X];
        for g in [
            ROOM,
            EmGeometry::SphereAtInfinity,
            EmGeometry::Ellipsoid {
                center: Vec3::ONE,
                radii: Vec3::ZERO,
            },
        ] {
            texgen(
                &g,
                Vec3::ONE,
                Vec3::new(0.0, 1.0, 3.0),
                &positions,
                &normals,
                &mut out,
            );
            assert!(
                out.iter().flatten().all(|v| v.is_finite()),
                "{g:?}: {out:?}"
            );
        }
    }

    #[test]
    fn texgen_where_computes_the_used_vertices_as_texgen_does() {
        let positions: Vec<Vec3> = (0..7)
            .map(|i| Vec3::new(i as f32 * 0.1 - 0.3, 0.2 + i as f32 * 0.05, 0.1))
            .collect();
        let normals: Vec<Vec3> = (0..7)
            .map(|i| Vec3::new(i as f32 * 0.3 - 1.0, 1.0, 0.5).normalize())
            .collect();
        let (origin, eye) = (Vec3::new(0.0, 0.25, 0.0), Vec3::new(0.4, 0.7, 1.5));
        let mut all = vec![[0.0; 4]; 7];
        texgen(&ROOM, origin, eye, &positions, &normals, &mut all);
        let used = [true, false, true, true, false, false, true];
        let mut some = vec![[9.0; 4]; 7];
        texgen_where(
            &ROOM,
            (origin, eye),
            (&positions, &normals),
            &used,
            &mut some,
        );
        for (k, u) in used.iter().enumerate() {
            let expected = if *u { all[k] } else { [9.0; 4] };
            assert_eq!(some[k], expected, "vertex {k}");
        }
    }

    #[test]
    fn bounding_ellipsoid_contains_points_and_fits_a_box_corner_set() {
        // The corners of a 2 x 1 x 0.5 box: minimal ellipsoid is the box
        // scaled by sqrt(3) (each corner on the surface).
        let half = Vec3::new(1.0, 0.5, 0.25);
        let pts: Vec<Vec3> = (0..8)
            .map(|i| {
                half * Vec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                )
            })
            .collect();
        let r = bounding_ellipsoid(Vec3::ZERO, &pts);
        let expected = half * 3f32.sqrt();
        assert!(
            (r - expected).abs().max_element() < 0.01 * expected.max_element(),
            "{r} vs {expected}"
        );
        for p in pts {
            assert!((p / r).length_squared() <= 1.0 + 1e-5);
        }
    }
}
