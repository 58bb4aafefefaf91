//! Per-frame CPU texgen for PEM playback, split over threads: each chunk
//! of vertices runs the (SIMD-per-vertex) texgen of `inference` into its
//! own slice of the output, so no locking and the same result as serial.

use glam::Vec3;
use inference::em_geometry::{EmGeometry, texgen};
use inference::texgen::TexgenVertex;
use rayon::prelude::*;

/// Vertices per task: large enough to amortise scheduling, small enough
/// to spread a 20k-vertex reflector over the cores.
const CHUNK: usize = 2048;

/// `[lookup, cos θ]` of every vertex against `geometry` (with EM origin
/// `origin`) into `out`, in parallel.
pub fn texgen_parallel(
    geometry: &EmGeometry,
    origin: Vec3,
    eye: Vec3,
    positions: &[Vec3],
    normals: &[Vec3],
    out: &mut [TexgenVertex],
) {
    out.par_chunks_mut(CHUNK)
        .zip(positions.par_chunks(CHUNK))
        .zip(normals.par_chunks(CHUNK))
        .for_each(|((o, p), n)| texgen(geometry, origin, eye, p, n, o));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_texgen_equals_serial() {
        let positions: Vec<Vec3> = (0..5000)
            .map(|i| Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.11).cos(), 0.3))
            .collect();
        let normals: Vec<Vec3> = positions.iter().map(|p| p.normalize_or_zero()).collect();
        let geometry = EmGeometry::Box {
            min: Vec3::splat(-4.0),
            max: Vec3::splat(4.0),
        };
        let eye = Vec3::new(0.5, 1.0, 3.0);
        let mut serial = vec![[0.0; 4]; positions.len()];
        let mut parallel = serial.clone();
        texgen(
            &geometry,
            Vec3::ZERO,
            eye,
            &positions,
            &normals,
            &mut serial,
        );
        texgen_parallel(
            &geometry,
            Vec3::ZERO,
            eye,
            &positions,
            &normals,
            &mut parallel,
        );
        assert_eq!(serial, parallel);
    }
}
