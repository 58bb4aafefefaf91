//! Camera intrinsics and the orbit: the 1D viewpoint parameter of the PEM paper.

use glam::{Mat4, Vec3};

use super::error::SceneError;
use super::ring_lines::RingLines;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub fov_y_deg: f32,
    pub near: f32,
    pub far: f32,
}

/// Viewpoints on a horizontal circle of `radius` around `center`, at height `height`;
/// azimuth line `i` sits at `start_deg + i · step_deg`. With `rings` > 1 the
/// viewpoint space is 2D: the circle repeated at elevations `j · ring_step_deg`
/// above the orbit plane (seen from `center`), sample `k` at azimuth line
/// `k % samples` of ring `k / samples`. With `azimuths` the lines sit
/// where those say (placed where the scene needs them); `start_deg` is
/// then the first and `step_deg` their mean spacing. Likewise with
/// `elevations` the rings sit where those say, the first at 0°, and
/// `ring_step_deg` is their mean spacing. With `ring_line_every` = n > 1
/// the rings above the first keep every n-th line only (and the last):
/// sample `k` runs over the first ring's lines, then each ring's own.
#[derive(Clone, Debug, PartialEq)]
pub struct Orbit {
    pub center: Vec3,
    pub radius: f32,
    pub height: f32,
    pub start_deg: f32,
    pub step_deg: f32,
    /// Azimuth lines per ring.
    pub samples: u32,
    /// Elevation rings (1: today's 1D orbit).
    pub rings: u32,
    pub ring_step_deg: f32,
    /// Explicit azimuth lines, degrees, increasing (`samples` of them).
    pub azimuths: Option<Vec<f32>>,
    /// Explicit ring elevations, degrees, increasing from 0 (`rings` of them).
    pub elevations: Option<Vec<f32>>,
    /// The rings above the first keep every this-many lines (1: all).
    pub ring_line_every: u32,
}

/// Keeps the eye off the poles, where a y-up look-at is undefined.
const MAX_ELEVATION_DEG: f32 = 89.0;

impl Orbit {
    /// Azimuth of line `sample` (not range-checked: off-manifold callers
    /// extrapolate by `step_deg` past the last explicit line).
    pub fn angle_deg(&self, sample: u32) -> f32 {
        match self.azimuths.as_deref() {
            Some([.., last]) if sample as usize >= self.azimuths_len() => {
                last + (sample as usize + 1 - self.azimuths_len()) as f32 * self.step_deg
            }
            Some(lines) if !lines.is_empty() => lines[sample as usize],
            _ => self.start_deg + sample as f32 * self.step_deg,
        }
    }

    fn azimuths_len(&self) -> usize {
        self.azimuths.as_ref().map_or(0, Vec::len)
    }

    /// The azimuth `t` of the way from line `line` to the next (the views
    /// between samples).
    pub fn between_deg(&self, line: u32, t: f32) -> f32 {
        let a = self.angle_deg(line);
        a + t * (self.angle_deg(line + 1) - a)
    }

    /// Eye position at azimuth `angle_deg` (0 = +z side of `center`, 90 = +x side).
    ///
    /// `elevation_deg` moves the eye off the orbit along the sphere through the orbit
    /// around `center`: 0 is the orbit itself (eye at `height`), positive rises above
    /// it, negative sinks below. The total elevation seen from `center` is clamped to
    /// ±89° so `view` stays well defined.
    pub fn eye(&self, angle_deg: f32, elevation_deg: f32) -> Vec3 {
        let dy = self.height - self.center.y;
        let sphere_radius = self.radius.hypot(dy);
        let base = dy.atan2(self.radius).to_degrees();
        let elevation = (base + elevation_deg)
            .clamp(-MAX_ELEVATION_DEG, MAX_ELEVATION_DEG)
            .to_radians();
        let azimuth = angle_deg.to_radians();
        let horizontal = sphere_radius * elevation.cos();
        self.center
            + Vec3::new(
                horizontal * azimuth.sin(),
                sphere_radius * elevation.sin(),
                horizontal * azimuth.cos(),
            )
    }

    /// Eye of orbit sample `sample`; an error outside `0..samples`.
    /// (azimuth, elevation above the orbit plane) of `eye`, degrees: the
    /// inverse of [`Orbit::eye`] (0, 0 at the centre itself).
    pub fn angles(&self, eye: Vec3) -> (f32, f32) {
        let d = eye - self.center;
        let dy = self.height - self.center.y;
        let base = dy.atan2(self.radius).to_degrees();
        let azimuth = d.x.atan2(d.z).to_degrees();
        let elevation = d.y.atan2(d.x.hypot(d.z)).to_degrees() - base;
        if azimuth.is_finite() && elevation.is_finite() && d.length_squared() > 0.0 {
            (azimuth, elevation)
        } else {
            (0.0, 0.0)
        }
    }

    pub fn sample_eye(&self, sample: u32) -> Result<Vec3, SceneError> {
        if sample >= self.sample_count() {
            return Err(SceneError::OrbitSampleOutOfRange {
                sample,
                samples: self.sample_count(),
            });
        }
        let (azimuth, elevation) = self.sample_angles(sample);
        Ok(self.eye(azimuth, elevation))
    }

    /// How the samples are numbered over the rings' lines.
    pub fn ring_lines(&self) -> RingLines {
        RingLines {
            lines: self.samples,
            every: self.ring_line_every,
        }
    }

    /// Every viewpoint sample: the first ring's lines, then each ring's.
    pub fn sample_count(&self) -> u32 {
        self.ring_lines().count(self.rings)
    }

    /// (azimuth line, ring) of sample `sample`.
    pub fn sample_line_ring(&self, sample: u32) -> (u32, u32) {
        self.ring_lines().coords(sample)
    }

    /// Sample `sample`'s place among its ring's samples, and their count
    /// (a ring's samples are numbered consecutively).
    pub fn ring_position(&self, sample: u32) -> (u32, u32) {
        self.ring_lines().position(sample)
    }

    /// (azimuth, elevation) of sample `sample`, degrees.
    pub fn sample_angles(&self, sample: u32) -> (f32, f32) {
        let (line, ring) = self.sample_line_ring(sample);
        (self.angle_deg(line), self.ring_elevation(ring))
    }

    /// Elevation of ring `ring`, degrees (not range-checked: past the last
    /// explicit ring it extrapolates by `ring_step_deg`).
    pub fn ring_elevation(&self, ring: u32) -> f32 {
        match self.elevations.as_deref() {
            Some(list @ [.., last]) => list
                .get(ring as usize)
                .copied()
                .unwrap_or(last + (ring as usize + 1 - list.len()) as f32 * self.ring_step_deg),
            _ => ring as f32 * self.ring_step_deg,
        }
    }

    /// The elevations of the rings, degrees (`[0]` for a 1D orbit).
    pub fn ring_elevations(&self) -> Vec<f32> {
        (0..self.rings.max(1))
            .map(|j| self.ring_elevation(j))
            .collect()
    }

    /// Whether every ring holds every line (a tensor grid: sample `k` at
    /// line `k % samples` of ring `k / samples`).
    pub fn is_tensor(&self) -> bool {
        self.rings <= 1 || self.ring_line_every <= 1
    }

    /// Right-handed world-to-view matrix looking from `eye` at `center`, y up (view space
    /// looks down −z). Always finite: straight above or below `center` the up vector
    /// becomes −z, and an eye at `center` looks down −z.
    pub fn view(&self, eye: Vec3) -> Mat4 {
        let dir = (self.center - eye).normalize_or(-Vec3::Z);
        let up = if dir.cross(Vec3::Y).length_squared() > 1e-10 {
            Vec3::Y
        } else {
            -Vec3::Z
        };
        glam::camera::rh::view::look_to_mat4(eye, dir, up)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orbit() -> Orbit {
        Orbit {
            center: Vec3::new(0.0, 0.3, 0.0),
            radius: 2.0,
            height: 1.0,
            start_deg: 10.0,
            step_deg: 1.0,
            samples: 100,
            rings: 1,
            ring_step_deg: 10.0,
            azimuths: None,
            elevations: None,
            ring_line_every: 1,
        }
    }

    #[test]
    fn explicit_lines_give_angles_between_views_and_extrapolate() {
        let o = Orbit {
            azimuths: Some(vec![0.0, 10.0, 14.0]),
            elevations: None,
            ring_line_every: 1,
            start_deg: 0.0,
            step_deg: 7.0,
            samples: 3,
            ..orbit()
        };
        assert_eq!(
            [0, 1, 2, 3, 4].map(|k| o.angle_deg(k)),
            [0.0, 10.0, 14.0, 21.0, 28.0]
        );
        assert_eq!(o.between_deg(0, 0.5), 5.0);
        assert_eq!(o.between_deg(1, 0.5), 12.0);
        assert_eq!(orbit().between_deg(3, 0.5), 13.5);
        assert!(o.sample_eye(2).is_ok() && o.sample_eye(3).is_err());
    }

    #[test]
    fn samples_lie_on_the_orbit() {
        let o = orbit();
        for s in [0, 37, 99] {
            let e = o.sample_eye(s).unwrap();
            assert!((e.y - 1.0).abs() < 1e-5);
            assert!(((e - o.center).with_y(0.0).length() - 2.0).abs() < 1e-5);
        }
        assert_eq!(o.angle_deg(5), 15.0);
        assert!(o.eye(0.0, 0.0).abs_diff_eq(Vec3::new(0.0, 1.0, 2.0), 1e-5));
        assert!(o.eye(90.0, 0.0).abs_diff_eq(Vec3::new(2.0, 1.0, 0.0), 1e-5));
    }

    #[test]
    fn angles_invert_eye() {
        let o = orbit();
        for (az, el) in [(0.0, 0.0), (37.5, 0.0), (80.0, 20.0), (-10.0, 30.0)] {
            let (a, e) = o.angles(o.eye(az, el));
            assert!(
                (a - az).abs() < 1e-3 && (e - el).abs() < 1e-3,
                "{az} {el}: {a} {e}"
            );
        }
        assert_eq!(o.angles(o.center), (0.0, 0.0));
    }

    #[test]
    fn out_of_range_sample_names_the_range() {
        let e = orbit().sample_eye(100).unwrap_err().to_string();
        assert_eq!(e, "orbit sample 100 out of range 0..100");
    }

    #[test]
    fn elevation_stays_on_sphere_and_is_clamped() {
        let o = orbit();
        let r = (o.eye(30.0, 0.0) - o.center).length();
        for el in [-200.0, -30.0, 10.0, 45.0, 1e9] {
            let e = o.eye(30.0, el);
            assert!(e.is_finite());
            assert!(((e - o.center).length() - r).abs() < 1e-4);
            assert!(o.view(e).is_finite());
        }
        assert!(o.view(o.center).is_finite());
        assert!(o.view(o.center + Vec3::Y).is_finite());
        assert!(o.eye(30.0, 10.0).y > o.eye(30.0, 0.0).y);
    }

    #[test]
    fn view_looks_at_center() {
        let o = orbit();
        let eye = o.sample_eye(3).unwrap();
        let v = o.view(eye);
        let c = v.transform_point3(o.center);
        // Right-handed view space looks down −z.
        assert!(c.x.abs() < 1e-5 && c.y.abs() < 1e-5 && c.z < 0.0);
        assert!(v.transform_point3(eye).length() < 1e-5);
    }
}
