//! A light that moves while the main job plays (`--light-path`): where it
//! is at each point of the path, and how the analytic room pass lights the
//! room with it (the relit panorama gives the reflector its environment).

use super::gpu::GpuLight;
use crate::shader_interface::RoomLight;
use glam::Vec3;
use inference::relight::grid::direction;

/// Intensity of the moving bulb (W·sr⁻¹) and irradiance of the sun
/// (W·m⁻²): the panorama is relit per unit, so these only scale the frame.
pub const BULB_INTENSITY: f32 = 8.0;
pub const SUN_IRRADIANCE: f32 = 3.0;

/// The paths a light can take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LightPath {
    /// A sun circling once while it rises from 20° to 60° elevation.
    Sun,
    /// A point light circling the reflector 2 m out, 1.5 m above its centre.
    Bulb,
}

impl LightPath {
    /// The light at `f` ∈ [0, 1) along the path around `origin` (the
    /// reflector's EM origin), for unit irradiance or `intensity`.
    pub fn light(self, origin: Vec3, f: f32, power: f32) -> GpuLight {
        match self {
            LightPath::Sun => GpuLight::Directional {
                to_light: direction(20.0 + 40.0 * f, 360.0 * f),
                irradiance: Vec3::splat(power),
            },
            LightPath::Bulb => {
                let a = std::f32::consts::TAU * f;
                GpuLight::Point {
                    position: origin + Vec3::new(2.0 * a.cos(), 1.5, 2.0 * a.sin()),
                    intensity: Vec3::splat(power),
                }
            }
        }
    }

    /// The light at `f` at the power the main job shows.
    pub fn shown(self, origin: Vec3, f: f32) -> GpuLight {
        let power = match self {
            LightPath::Sun => SUN_IRRADIANCE,
            LightPath::Bulb => BULB_INTENSITY,
        };
        self.light(origin, f, power)
    }
}

/// The analytic room shader's light block for `light` (`shaders/room.frag`):
/// a point light as an isotropic emitter (`position.w = 1`, no emitter
/// cosine), a sun as a direction (`position.w = 0`, xyz towards the light). The ambient
/// term follows the scene light's convention (`passes::room`): the light's
/// flux spread evenly over the room's `room_area`, as radiance per unit
/// albedo — `4I/A` for a point light, and for a sun through the open box
/// the mean over its six faces of `E·max(n·L, 0)`, over π.
pub fn room_light(light: GpuLight, room_area: f32) -> RoomLight {
    match light {
        GpuLight::Point {
            position,
            intensity,
        } => RoomLight {
            position: position.extend(1.0),
            normal: glam::Vec4::new(0.0, 0.0, 0.0, 4.0 / room_area.max(1e-6)),
            radiance: intensity.extend(0.0),
        },
        GpuLight::Directional {
            to_light,
            irradiance,
        } => {
            let l = to_light.normalize_or(Vec3::Y);
            let mean_cos = (l.x.abs() + l.y.abs() + l.z.abs()) / 6.0;
            RoomLight {
                position: l.extend(0.0),
                normal: Vec3::ZERO.extend(mean_cos / std::f32::consts::PI),
                radiance: irradiance.extend(0.0),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paths_move_the_light_and_the_room_block_encodes_its_kind() {
        let origin = Vec3::new(0.0, 0.25, 0.0);
        for path in [LightPath::Sun, LightPath::Bulb] {
            let (a, b) = (path.shown(origin, 0.0), path.shown(origin, 0.3));
            assert_ne!(a, b, "{path:?} moves");
        }
        let GpuLight::Point { position, .. } = LightPath::Bulb.shown(origin, 0.25) else {
            panic!("a bulb is a point light");
        };
        assert!((position - origin - Vec3::new(0.0, 1.5, 2.0)).length() < 1e-5);
        let sun = room_light(LightPath::Sun.shown(origin, 0.0), 160.0);
        assert_eq!(sun.position.w, 0.0, "a sun is a direction");
        assert!(
            (sun.position.truncate().length() - 1.0).abs() < 1e-5,
            "unit: d² = 1"
        );
        assert!(
            sun.position.y > 0.3,
            "the sun is above the horizon: {sun:?}"
        );
        assert_eq!(sun.radiance.w, 0.0, "no emitter cosine");
        let bulb = room_light(LightPath::Bulb.shown(origin, 0.0), 160.0);
        assert_eq!(
            (bulb.position.w, bulb.radiance.w),
            (1.0, 0.0),
            "a point, no cosine"
        );
        assert_eq!(bulb.normal.truncate(), Vec3::ZERO, "isotropic");
        assert!((bulb.normal.w - 4.0 / 160.0).abs() < 1e-7);
        assert!(sun.normal.w > 0.0 && sun.normal.w < 1.0 / std::f32::consts::PI);
        assert_eq!(bulb.radiance.x, BULB_INTENSITY);
    }
}
