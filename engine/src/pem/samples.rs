//! Which viewpoint samples a frame draws from, and with what weights: the
//! two samples nearest the eye's azimuth along the orbit, blended by
//! distance (PEM paper §5). Eyes beyond the first or last sample clamp to
//! it; an eye exactly on a sample draws that sample alone.

use glam::Vec3;
use inference::scene::Orbit;

/// Weights below this (in sample spacings) count as "exactly on a sample":
/// no blend pass is drawn.
pub const ON_SAMPLE: f32 = 1e-4;

/// The samples of one frame: `first` drawn with weight `1 − w`, and
/// `second = (sample, w)` blended over it when the eye is between samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleBlend {
    pub first: u32,
    pub second: Option<(u32, f32)>,
}

impl SampleBlend {
    pub fn samples(&self) -> impl Iterator<Item = u32> {
        std::iter::once(self.first).chain(self.second.map(|(s, _)| s))
    }
}

/// The eye's position along the orbit in samples (0 = first sample),
/// clamped to `[0, samples − 1]`; finite for every input. Azimuths wrap
/// around the middle of the orbit so an eye "before" the first sample
/// clamps to it rather than to the last.
pub fn orbit_position(orbit: &Orbit, eye: Vec3) -> f32 {
    let last = orbit.samples.saturating_sub(1) as f32;
    if orbit.step_deg == 0.0 || !orbit.step_deg.is_finite() || last == 0.0 {
        return 0.0;
    }
    let d = eye - orbit.center;
    let azimuth = d.x.atan2(d.z).to_degrees();
    let middle = orbit.start_deg + orbit.step_deg * last * 0.5;
    let relative = (azimuth - middle + 180.0).rem_euclid(360.0) - 180.0;
    let p = (middle + relative - orbit.start_deg) / orbit.step_deg;
    if p.is_finite() {
        p.clamp(0.0, last)
    } else {
        0.0
    }
}

/// The samples drawn for `eye` when only every `spacing`-th sample is used
/// (spacing 0 counts as 1), blending the two nearest or taking the nearest.
pub fn sample_blend(orbit: &Orbit, eye: Vec3, spacing: u32, blend: bool) -> SampleBlend {
    let s = spacing.max(1);
    let last = (orbit.samples.saturating_sub(1) / s) * s;
    let p = orbit_position(orbit, eye).min(last as f32);
    let lo = ((p / s as f32).floor() as u32 * s).min(last);
    let hi = (lo + s).min(last);
    let t = if hi == lo {
        0.0
    } else {
        ((p - lo as f32) / s as f32).clamp(0.0, 1.0)
    };
    let (near, far, w) = if t <= 0.5 {
        (lo, hi, t)
    } else {
        (hi, lo, 1.0 - t)
    };
    SampleBlend {
        first: near,
        second: (blend && w >= ON_SAMPLE && far != near).then_some((far, w)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orbit() -> Orbit {
        Orbit {
            center: Vec3::new(0.0, 0.25, 0.0),
            radius: 1.5,
            height: 0.7,
            start_deg: 0.0,
            step_deg: 1.0,
            samples: 100,
        }
    }

    #[test]
    fn exactly_on_a_sample_draws_it_alone() {
        let o = orbit();
        for k in [0, 1, 37, 98, 99] {
            let eye = o.sample_eye(k).expect("in range");
            let b = sample_blend(&o, eye, 1, true);
            assert_eq!(
                b,
                SampleBlend {
                    first: k,
                    second: None
                },
                "sample {k}"
            );
        }
    }

    #[test]
    fn between_samples_blends_the_two_nearest_by_distance() {
        let o = orbit();
        let b = sample_blend(&o, o.eye(10.25, 0.0), 1, true);
        assert_eq!(b.first, 10);
        let (second, w) = b.second.expect("a blend pass");
        assert_eq!(second, 11);
        assert!((w - 0.25).abs() < 1e-3, "{w}");
        let b = sample_blend(&o, o.eye(10.75, 0.0), 1, true);
        assert_eq!(b.first, 11);
        assert!((b.second.expect("blend").1 - 0.25).abs() < 1e-3);
        // Without blending, the nearest alone.
        let b = sample_blend(&o, o.eye(10.75, 0.0), 1, false);
        assert_eq!(
            b,
            SampleBlend {
                first: 11,
                second: None
            }
        );
    }

    #[test]
    fn elevation_keeps_the_azimuth() {
        let o = orbit();
        let b = sample_blend(&o, o.eye(42.5, 30.0), 1, true);
        assert_eq!(b.samples().collect::<Vec<_>>().len(), 2);
        assert!((b.second.expect("blend").1 - 0.5).abs() < 1e-3);
    }

    #[test]
    fn views_beyond_the_orbit_clamp_to_its_ends() {
        let o = orbit();
        for (angle, expected) in [(-5.0, 0), (-100.0, 0), (99.0, 99), (140.0, 99), (200.0, 99)] {
            let b = sample_blend(&o, o.eye(angle, 0.0), 1, true);
            assert_eq!(
                b,
                SampleBlend {
                    first: expected,
                    second: None
                },
                "{angle}°"
            );
        }
        // Straight above the centre, at the centre, and non-finite eyes stay in range.
        for eye in [
            o.center + Vec3::Y,
            o.center,
            Vec3::splat(f32::NAN),
            Vec3::splat(f32::INFINITY),
        ] {
            let b = sample_blend(&o, eye, 1, true);
            assert!(b.samples().all(|s| s < o.samples), "{eye}: {b:?}");
        }
    }

    #[test]
    fn sample_spacing_uses_every_nth_sample_only() {
        let o = orbit();
        let b = sample_blend(&o, o.eye(13.0, 0.0), 4, true);
        assert_eq!(b.first, 12);
        let (second, w) = b.second.expect("blend");
        assert_eq!(second, 16);
        assert!((w - 0.25).abs() < 1e-3);
        // The grid's last sample (96) is the end: 99 clamps to it.
        let b = sample_blend(&o, o.eye(99.0, 0.0), 4, true);
        assert_eq!(
            b,
            SampleBlend {
                first: 96,
                second: None
            }
        );
        // Degenerate orbits.
        let one = Orbit { samples: 1, ..o };
        assert_eq!(sample_blend(&one, o.eye(50.0, 0.0), 1, true).first, 0);
        let flat = Orbit { step_deg: 0.0, ..o };
        assert_eq!(sample_blend(&flat, o.eye(50.0, 0.0), 0, true).first, 0);
    }
}
