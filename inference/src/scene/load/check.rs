//! Small value checks shared by the loader; each error names the file and field.

use glam::Vec3;

use super::Loader;
use crate::scene::error::SceneError;
use crate::scene::file::V3;

impl Loader<'_> {
    pub(super) fn err(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            scene: self.origin.clone(),
            field: field.into(),
            message: message.into(),
        }
    }

    /// `value` of `field` inside `range`, else an error naming what was
    /// expected (`what`, e.g. "levels") and the range's ends.
    pub(super) fn in_range(
        &self,
        field: String,
        value: f32,
        range: &std::ops::RangeInclusive<f32>,
        what: &str,
    ) -> Result<(), SceneError> {
        if range.contains(&value) {
            return Ok(());
        }
        Err(self.err(
            field,
            format!(
                "{value} (expected {what} from {} to {})",
                range.start(),
                range.end()
            ),
        ))
    }

    pub(super) fn vec3(&self, field: &str, v: V3) -> Result<Vec3, SceneError> {
        let v = Vec3::from_array(v);
        if !v.is_finite() {
            return Err(self.err(
                field,
                format!("{} is not finite (expected numbers)", toml3(v)),
            ));
        }
        Ok(v)
    }

    /// Finite, each component in `[lo, hi]` (`hi` = `f32::MAX`: no bound
    /// above, and none named).
    pub(super) fn vec3_in(&self, field: &str, v: V3, lo: f32, hi: f32) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v)?;
        if v.cmplt(Vec3::splat(lo)).any() || v.cmpgt(Vec3::splat(hi)).any() {
            let expected = if hi == f32::MAX {
                format!("each component at least {lo}")
            } else {
                format!("each component from {lo} to {hi}")
            };
            return Err(self.err(field, format!("{} (expected {expected})", toml3(v))));
        }
        Ok(v)
    }

    pub(super) fn finite(&self, field: &str, x: f32) -> Result<f32, SceneError> {
        if !x.is_finite() {
            return Err(self.err(field, format!("{x} is not finite")));
        }
        Ok(x)
    }

    pub(super) fn positive(&self, field: &str, x: f32) -> Result<f32, SceneError> {
        if !(x > 0.0 && x.is_finite()) {
            return Err(self.err(field, format!("{x} must be positive and finite")));
        }
        Ok(x)
    }

    /// Every viewpoint sample's eye lies inside the room box: from outside,
    /// the room's walls (drawn from inside) would hide the scene.
    pub(super) fn check_eyes_in_room(
        &self,
        orbit: &crate::scene::Orbit,
        (min, max): (Vec3, Vec3),
    ) -> Result<(), SceneError> {
        for k in 0..orbit.sample_count() {
            let eye = orbit.sample_eye(k)?;
            if !(eye.cmpgt(min).all() && eye.cmplt(max).all()) {
                return Err(self.err(
                    "orbit",
                    format!(
                        "sample {k}'s eye at {} lies outside the room {}..{} (expected \
                         center, radius, height and rings that keep every eye inside it)",
                        toml3(eye),
                        toml3(min),
                        toml3(max)
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// `v` as a scene file writes it: `[x, y, z]`.
pub(super) fn toml3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}
