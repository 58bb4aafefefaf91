//! Indexed triangle mesh, the unit every consumer (rasteriser, tracer, texgen) works on.

use glam::{Affine3A, Vec2, Vec3};

/// Triangle list with per-vertex attributes; `normals` and `uvs` have one entry per position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Corner positions of triangle `t` (panics if `t >= triangle_count()`, like indexing).
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let i = &self.indices[3 * t..3 * t + 3];
        [
            self.positions[i[0] as usize],
            self.positions[i[1] as usize],
            self.positions[i[2] as usize],
        ]
    }

    /// Total surface area.
    pub fn area(&self) -> f32 {
        (0..self.triangle_count())
            .map(|t| triangle_area(self.triangle(t)))
            .sum()
    }

    /// Area-weighted mean of triangle centroids: the PEM paper's EM origin.
    /// Falls back to the mean position when the area is zero, and to the origin when empty.
    pub fn area_weighted_centroid(&self) -> Vec3 {
        Self::centroid_of([self])
    }

    /// [`Mesh::area_weighted_centroid`] of several meshes taken as one (a
    /// reflector's parts); of one mesh, bit for bit its own.
    pub fn centroid_of<'a>(meshes: impl IntoIterator<Item = &'a Mesh> + Clone) -> Vec3 {
        let (mut sum, mut total) = (Vec3::ZERO, 0.0f64);
        for mesh in meshes.clone() {
            for t in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(t);
                let area = triangle_area([a, b, c]) as f64;
                sum += (a + b + c) / 3.0 * area as f32;
                total += area;
            }
        }
        if total > 0.0 {
            return sum / total as f32;
        }
        let count: usize = meshes.clone().into_iter().map(|m| m.positions.len()).sum();
        if count == 0 {
            return Vec3::ZERO;
        }
        let positions: Vec3 = meshes
            .into_iter()
            .flat_map(|m| m.positions.iter().copied())
            .sum();
        positions / count as f32
    }

    /// The box around several meshes (empty ones add nothing).
    pub fn bounds_of<'a>(meshes: impl IntoIterator<Item = &'a Mesh>) -> (Vec3, Vec3) {
        meshes
            .into_iter()
            .filter(|m| !m.positions.is_empty())
            .map(Mesh::bounds)
            .reduce(|(a0, a1), (b0, b1)| (a0.min(b0), a1.max(b1)))
            .unwrap_or((Vec3::ZERO, Vec3::ZERO))
    }

    /// Axis-aligned bounds `(min, max)`; `(0, 0)` for an empty mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        self.positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            })
    }

    /// Applies a rigid-plus-uniform-scale transform (normals stay unit length).
    pub fn transform(&mut self, m: &Affine3A) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = m.transform_vector3(*n).normalize_or(*n);
        }
    }
}

pub fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

/// True when a triangle has (numerically) no area: coincident corners or collinear ones.
/// Relative to the longest edge so the test is scale-free.
pub fn is_degenerate([a, b, c]: [Vec3; 3]) -> bool {
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    let twice_area = (b - a).cross(c - a).length();
    // Written so that NaN corners count as degenerate.
    let well_shaped = twice_area > 1e-7 * longest;
    !well_shaped
}

/// Normalises a file's normal, but leaves already-unit normals bit-exact (so write → load round-trips);
/// zero stays zero and is filled in from the faces later.
pub(crate) fn unit(n: Vec3) -> Vec3 {
    if (n.length_squared() - 1.0).abs() < 1e-6 {
        n
    } else {
        n.normalize_or_zero()
    }
}

/// Replaces zero normals with the area-weighted average of adjacent face normals.
pub(crate) fn fill_missing_normals(mesh: &mut Mesh) {
    let mut sum = vec![Vec3::ZERO; mesh.positions.len()];
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
        let n = (b - a).cross(c - a); // length = twice the area: area weighting for free
        for &i in tri {
            sum[i as usize] += n;
        }
    }
    for (n, s) in mesh.normals.iter_mut().zip(sum) {
        if *n == Vec3::ZERO {
            *n = s.normalize_or(Vec3::Y);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 2.0),
                Vec3::new(0.0, 0.0, 2.0),
                Vec3::new(100.0, 5.0, 0.0), // unreferenced: must not move the centroid
            ],
            normals: vec![Vec3::Y; 5],
            uvs: vec![Vec2::ZERO; 5],
            indices: vec![0, 2, 1, 0, 3, 2],
        }
    }

    #[test]
    fn centroid_area_bounds() {
        let m = quad();
        assert_eq!(m.triangle_count(), 2);
        assert!((m.area() - 4.0).abs() < 1e-6);
        assert!(
            m.area_weighted_centroid()
                .abs_diff_eq(Vec3::new(1.0, 0.0, 1.0), 1e-6)
        );
        assert_eq!(m.bounds(), (Vec3::ZERO, Vec3::new(100.0, 5.0, 2.0)));
        assert_eq!(Mesh::default().bounds(), (Vec3::ZERO, Vec3::ZERO));
        assert_eq!(Mesh::default().area_weighted_centroid(), Vec3::ZERO);
    }

    #[test]
    fn degenerate_detection() {
        let a = Vec3::ZERO;
        let b = Vec3::X;
        assert!(is_degenerate([a, a, b]));
        assert!(is_degenerate([a, b, 2.0 * b]));
        assert!(is_degenerate([a, a, a]));
        assert!(is_degenerate([a, b, Vec3::new(f32::NAN, 0.0, 0.0)]));
        assert!(!is_degenerate([a, b, Vec3::Y]));
        // Tiny but well-shaped triangles are fine.
        assert!(!is_degenerate([a, b * 1e-6, Vec3::Y * 1e-6]));
    }
}
