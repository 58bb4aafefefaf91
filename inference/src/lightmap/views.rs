//! The viewpoints a light map is made for: azimuths across the orbit and
//! elevations from the orbit plane up to [`MAX_ELEVATION_DEG`] above it
//! (the viewpoint space playback moves in). A dense grid is only ray-cast
//! (where is each surface seen, how finely); a few of its views are traced
//! and stacked into the solve.

use crate::scene::Orbit;
use glam::Vec3;

/// The highest elevation above the orbit plane the light maps serve at
/// least (playback's default path and eval's views reach 30°); an orbit
/// whose rings reach higher raises it (see [`max_elevation_deg`]).
pub const MAX_ELEVATION_DEG: f32 = 30.0;

/// The highest elevation the light maps of `orbit` serve: 30°, or its top
/// ring's elevation when that is higher.
pub fn max_elevation_deg(orbit: &Orbit) -> f32 {
    let top = orbit.ring_elevation(orbit.rings.saturating_sub(1));
    MAX_ELEVATION_DEG.max(top)
}
/// Surveyed grid: azimuths × elevations.
const SURVEY_AZIMUTHS: u32 = 12;
const SURVEY_ELEVATIONS: u32 = 4;
/// Stacked views: azimuths × elevations.
pub const SOLVE_AZIMUTHS: u32 = 5;
pub const SOLVE_ELEVATIONS: u32 = 2;

/// An eye on the viewpoint space: azimuth on the orbit, elevation above it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewpoint {
    pub azimuth_deg: f32,
    pub elevation_deg: f32,
}

impl Viewpoint {
    pub fn eye(&self, orbit: &Orbit) -> Vec3 {
        orbit.eye(self.azimuth_deg, self.elevation_deg)
    }
}

/// `n` values from `lo` to `hi`, ends included (the middle for n = 1).
fn spread(lo: f32, hi: f32, n: u32) -> Vec<f32> {
    if n <= 1 {
        return vec![0.5 * (lo + hi)];
    }
    (0..n)
        .map(|i| lo + (hi - lo) * i as f32 / (n - 1) as f32)
        .collect()
}

fn grid(orbit: &Orbit, azimuths: u32, elevations: u32) -> Vec<Viewpoint> {
    let first = orbit.angle_deg(0);
    let last = orbit.angle_deg(orbit.samples.saturating_sub(1));
    let mut out = Vec::new();
    for elevation_deg in spread(0.0, max_elevation_deg(orbit), elevations) {
        for azimuth_deg in spread(first, last, azimuths) {
            out.push(Viewpoint {
                azimuth_deg: azimuth_deg + 0.0,
                elevation_deg: elevation_deg + 0.0,
            });
        }
    }
    out
}

/// The views whose rays decide each chart's stored part and resolution.
pub fn survey_views(orbit: &Orbit) -> Vec<Viewpoint> {
    grid(orbit, SURVEY_AZIMUTHS, SURVEY_ELEVATIONS)
}

/// The views traced and stacked into each light map's solve: five azimuths
/// from the orbit's first to its last line, on the orbit plane and at the
/// highest elevation.
pub fn solve_views(orbit: &Orbit) -> Vec<Viewpoint> {
    grid(orbit, SOLVE_AZIMUTHS, SOLVE_ELEVATIONS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_span_the_orbit_and_the_elevations() {
        let orbit = crate::scene::Scene::load("teapot").expect("teapot").orbit;
        let v = solve_views(&orbit);
        assert_eq!(v.len(), (SOLVE_AZIMUTHS * SOLVE_ELEVATIONS) as usize);
        assert_eq!(
            v[0],
            Viewpoint {
                azimuth_deg: 0.0,
                elevation_deg: 0.0
            }
        );
        let last = v.len() - 1;
        assert_eq!(v[SOLVE_AZIMUTHS as usize - 1].azimuth_deg, 99.0);
        assert_eq!(v[last].elevation_deg, MAX_ELEVATION_DEG);
        let s = survey_views(&orbit);
        assert_eq!(s.len(), 48);
        assert!(s.iter().all(|p| (0.0..=99.0).contains(&p.azimuth_deg)));
        // A one-sample orbit still has views (all at its one azimuth).
        let one = crate::scene::Orbit {
            samples: 1,
            ..orbit.clone()
        };
        assert!(solve_views(&one).iter().all(|p| p.azimuth_deg == 0.0));
        // Rings above 30° raise the highest views to the top ring.
        let rings = crate::scene::Orbit {
            rings: 6,
            ring_step_deg: 10.0,
            ..orbit
        };
        assert_eq!(solve_views(&rings)[5].elevation_deg, 50.0);
    }
}
