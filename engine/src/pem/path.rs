//! The default playback path: first along the orbit through every sample,
//! then rising above the orbit's plane while it turns back, so the same run
//! shows on-manifold views, views between samples and views off the
//! manifold (PEM paper §5).

use inference::scene::Orbit;

/// How high the path climbs above the orbit plane, in degrees.
pub const RISE_DEG: f32 = 20.0;
/// Share of the frames spent on the orbit itself.
const ON_ORBIT: f32 = 2.0 / 3.0;

/// (azimuth, elevation) in degrees of frame `i` of `frames`.
pub fn path_view(orbit: &Orbit, i: u32, frames: u32) -> (f32, f32) {
    let first = orbit.angle_deg(0);
    let last = orbit.angle_deg(orbit.samples.saturating_sub(1));
    if frames <= 1 {
        return (first, 0.0);
    }
    let t = i.min(frames - 1) as f32 / (frames - 1) as f32;
    if t <= ON_ORBIT {
        (first + (last - first) * t / ON_ORBIT, 0.0)
    } else {
        // Back towards the middle while climbing.
        let u = (t - ON_ORBIT) / (1.0 - ON_ORBIT);
        let middle = 0.5 * (first + last);
        (last + (middle - last) * u, RISE_DEG * u)
    }
}

/// Frames of the default run: half again the sample count, every ring's
/// samples counted (at least 2); with sparse upper rings, the first ring's
/// (the path runs along its lines).
pub fn default_frames(orbit: &Orbit) -> u32 {
    let n = match orbit.is_tensor() {
        true => orbit.sample_count(),
        false => orbit.samples,
    };
    (n + n / 2).max(2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn path_visits_the_orbit_then_rises() {
        let o = Orbit {
            center: Vec3::ZERO,
            radius: 1.0,
            height: 0.5,
            start_deg: 0.0,
            step_deg: 1.0,
            samples: 100,
            rings: 1,
            ring_step_deg: 10.0,
            azimuths: None,
            elevations: None,
            ring_line_every: 1,
        };
        let frames = default_frames(&o);
        assert_eq!(frames, 150);
        assert_eq!(path_view(&o, 0, frames), (0.0, 0.0));
        let (a, e) = path_view(&o, 99, frames);
        assert!((a - 99.0 * 99.0 / (149.0 * ON_ORBIT)).abs() < 1e-3 && e == 0.0);
        let (a, e) = path_view(&o, frames - 1, frames);
        assert!((a - 49.5).abs() < 1e-4 && (e - RISE_DEG).abs() < 1e-4);
        // Every view finite, elevation never negative, beyond the end clamps.
        for i in 0..frames + 3 {
            let (a, e) = path_view(&o, i, frames);
            assert!(a.is_finite() && e.is_finite() && (0.0..=RISE_DEG).contains(&e));
        }
        assert_eq!(path_view(&o, 5, 1), (0.0, 0.0));
    }
}
