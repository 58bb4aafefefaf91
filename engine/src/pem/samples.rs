//! Which viewpoint samples a frame draws from, and with what weights: the
//! three samples of the triangle of the view grid that holds the eye
//! (`ViewBlend::Triangles`, the default) or the four corners of its cell,
//! bilinearly (PEM paper §5); a 1D orbit blends the two nearest. Eyes
//! beyond the grid clamp to its edge; an eye exactly on a sample draws
//! that sample alone. The grid math lives in `inference::scene::grid`.

pub use inference::scene::grid::ON_SAMPLE;
pub use inference::scene::{SampleBlend, ViewBlend, ViewGrid};

use glam::Vec3;
use inference::scene::Orbit;

/// The samples of `grid` (on `orbit`'s sphere of views) an eye at `eye`
/// draws, every `spacing`-th line only, blended by `rule` or the nearest
/// alone.
pub fn sample_blend(
    grid: &ViewGrid,
    orbit: &Orbit,
    eye: Vec3,
    spacing: u32,
    blend: bool,
    rule: ViewBlend,
) -> SampleBlend {
    let (azimuth, elevation) = orbit.angles(eye);
    grid.blend_by(azimuth, elevation, spacing, blend, rule)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bilinear(grid: &ViewGrid, orbit: &Orbit, eye: Vec3) -> SampleBlend {
        sample_blend(grid, orbit, eye, 1, true, ViewBlend::Bilinear)
    }

    #[test]
    fn eyes_map_to_their_grid_cell() {
        let orbit = Orbit {
            center: Vec3::new(0.0, 0.25, 0.0),
            radius: 1.5,
            height: 0.7,
            start_deg: 0.0,
            step_deg: 1.0,
            samples: 100,
            rings: 1,
            ring_step_deg: 10.0,
            azimuths: None,
            elevations: None,
            ring_line_every: 1,
        };
        let grid = ViewGrid::from_orbit(&orbit);
        for k in [0, 37, 99] {
            let eye = orbit.sample_eye(k).expect("in range");
            assert_eq!(bilinear(&grid, &orbit, eye), SampleBlend::one(k));
        }
        let b = bilinear(&grid, &orbit, orbit.eye(10.25, 0.0));
        assert_eq!(b.indices().collect::<Vec<_>>(), [10, 11]);
        // Straight above the centre, at the centre, non-finite eyes: in range.
        for eye in [orbit.center + Vec3::Y, orbit.center, Vec3::splat(f32::NAN)] {
            let b = bilinear(&grid, &orbit, eye);
            assert!(b.indices().all(|k| k < grid.len()), "{eye}: {b:?}");
        }
    }

    #[test]
    fn a_view_between_rings_blends_the_corners_of_its_cell() {
        let orbit = Orbit {
            center: Vec3::new(0.0, 0.25, 0.0),
            radius: 1.5,
            height: 0.7,
            start_deg: 0.0,
            step_deg: 4.0,
            samples: 10,
            rings: 3,
            ring_step_deg: 10.0,
            azimuths: None,
            elevations: None,
            ring_line_every: 1,
        };
        let grid = ViewGrid::from_orbit(&orbit);
        assert_eq!(grid.len(), orbit.sample_count());
        // Every sample's own eye plays that sample alone, on every ring.
        for k in [0, 9, 10, 23, 29] {
            let eye = orbit.sample_eye(k).expect("in range");
            let b = bilinear(&grid, &orbit, eye);
            assert_eq!(b.indices().collect::<Vec<_>>(), [k], "{k}: {b:?}");
        }
        // Half-way in azimuth and elevation: four equal corners.
        let b = bilinear(&grid, &orbit, orbit.eye(14.0, 15.0));
        let mut corners: Vec<u32> = b.indices().collect();
        corners.sort();
        assert_eq!(corners, [13, 14, 23, 24], "{b:?}");
        assert!(b.samples.iter().all(|s| (s.1 - 0.25).abs() < 1e-3), "{b:?}");
        // The default rule: three of those corners, the eye their mean.
        let eye = orbit.eye(14.5, 16.0);
        let b = sample_blend(&grid, &orbit, eye, 1, true, ViewBlend::default());
        assert_eq!(b.samples.len(), 3, "{b:?}");
        assert!(b.indices().all(|k| [13, 14, 23, 24].contains(&k)), "{b:?}");
        let mean = b.samples.iter().fold(Vec3::ZERO, |m, &(k, w)| {
            let (az, el) = grid.angles(k);
            m + w * Vec3::new(az, el, 0.0)
        });
        assert!(mean.abs_diff_eq(Vec3::new(14.5, 16.0, 0.0), 1e-2), "{mean}");
        // Above the top ring clamps to it.
        let b = bilinear(&grid, &orbit, orbit.eye(8.0, 40.0));
        assert_eq!(b.indices().collect::<Vec<_>>(), [22], "{b:?}");
    }
}
