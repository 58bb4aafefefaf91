//! The greedy two-path shading model (thesis §6.2): from the first hit,
//! one path starts by reflection and one by refraction; at every later
//! interface each follows the child with the larger Fresnel coefficient,
//! until it leaves the lens. The pixel is `T·F_T·G_T + R·F_R·G_R`: F the
//! product of the coefficients taken, G the per-channel absorption
//! `exp(−σ·length)` over the glass crossed, T and R the radiance along the
//! two exit rays. Fresnel, offsets and directions are the tracer's own.

use glam::Vec3;

use super::lens::{Lens, Surface};
use crate::trace::optics::{dielectric, offset, reflect, refract};

/// How a path went: the child taken at each interface (bit i set =
/// reflection at interface i), how many interfaces, and whether it left
/// the lens. Paths of different topology are not interpolated across.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Topology {
    pub choices: u32,
    pub interfaces: u8,
    pub exited: bool,
}

/// One greedy path's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Path {
    /// `F·G` per channel; 0 when the path never leaves the lens.
    pub weight: Vec3,
    /// Where and in which (unit) direction it leaves the lens; for a path
    /// that never does, its last ray (weight 0, kept finite for lookups).
    pub origin: Vec3,
    pub dir: Vec3,
    pub topology: Topology,
}

impl Path {
    pub fn exited(&self) -> bool {
        self.topology.exited
    }
}

/// The two paths of one first hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoPaths {
    /// Starting by refraction (`T·F_T·G_T`).
    pub t: Path,
    /// Starting by reflection (`R·F_R·G_R`).
    pub r: Path,
}

/// The two paths of a ray along `dir` arriving at `s` (a vertex, or a hit
/// found by a camera ray), `on` the lens triangle `s` lies on when known
/// (rays leaving it outwards may then skip their traversal).
pub fn two_paths(lens: &Lens, s: &Surface, dir: Vec3, on: Option<u32>) -> TwoPaths {
    let cos_i = s.ns.dot(-dir).clamp(0.0, 1.0);
    let (f, cos_t) = dielectric(lens.ior, cos_i, s.front);
    let reflected = (reflect(dir, s.ns).normalize_or(s.ng), offset(s.p, s.ng));
    let r = follow(
        lens,
        reflected,
        Vec3::splat(f),
        s.medium_after_reflection(lens),
        1,
        1,
        on,
    );
    let t = match cos_t {
        Some(cos_t) if f < 1.0 => {
            let d = refract(dir, s.ns, lens.ior, s.front, cos_i, cos_t);
            let medium = s.front.then_some(lens.absorption);
            follow(
                lens,
                (d, offset(s.p, -s.ng)),
                Vec3::splat(1.0 - f),
                medium,
                0,
                1,
                on,
            )
        }
        // Total internal reflection or grazing: nothing is transmitted.
        _ => Path {
            weight: Vec3::ZERO,
            origin: reflected.1,
            dir: reflected.0,
            topology: Topology {
                choices: 0,
                interfaces: 1,
                exited: false,
            },
        },
    };
    TwoPaths { t, r }
}

impl Surface {
    /// The medium a reflected ray travels in: glass when the ray was inside.
    fn medium_after_reflection(&self, lens: &Lens) -> Option<Vec3> {
        (!self.front).then_some(lens.absorption)
    }
}

/// Follows one path from its first child ray `(dir, origin)` with weight
/// `weight` so far, inside glass when `medium` is set; `choices` and
/// `interfaces` describe the first interface; `on` is the lens triangle the
/// ray starts from, when known.
fn follow(
    lens: &Lens,
    (mut dir, mut origin): (Vec3, Vec3),
    mut weight: Vec3,
    mut medium: Option<Vec3>,
    mut choices: u32,
    mut interfaces: u8,
    mut on: Option<u32>,
) -> Path {
    loop {
        // Out of the lens. (Through a hole of an open mesh the tracer would
        // still absorb along the way to the room; the model stops here.)
        // Leaving a hull triangle outwards needs no traversal to know it.
        let escapes = on.is_some_and(|t| lens.escapes(t, origin, dir));
        let hit = if escapes {
            None
        } else {
            lens.closest(origin, dir)
        };
        let Some(hit) = hit else {
            return Path {
                weight,
                origin,
                dir,
                topology: Topology {
                    choices,
                    interfaces,
                    exited: true,
                },
            };
        };
        if let Some(sigma) = medium {
            weight *= (-sigma * hit.t).exp();
        }
        if u32::from(interfaces) >= lens.max_interfaces {
            return Path {
                weight: Vec3::ZERO,
                origin,
                dir,
                topology: Topology {
                    choices,
                    interfaces,
                    exited: false,
                },
            };
        }
        let s = lens.surface(&hit, dir);
        on = Some(hit.prim.triangle);
        let cos_i = s.ns.dot(-dir).clamp(0.0, 1.0);
        let (f, cos_t) = dielectric(lens.ior, cos_i, s.front);
        match cos_t {
            // The greedy choice: the child with the larger coefficient.
            Some(cos_t) if 1.0 - f >= f => {
                weight *= 1.0 - f;
                medium = s.front.then_some(lens.absorption);
                dir = refract(dir, s.ns, lens.ior, s.front, cos_i, cos_t);
                origin = offset(s.p, -s.ng);
            }
            _ => {
                weight *= f;
                choices |= 1 << interfaces.min(31);
                dir = reflect(dir, s.ns).normalize_or(s.ng);
                origin = offset(s.p, s.ng);
            }
        }
        interfaces = interfaces.saturating_add(1);
    }
}

/// The two paths of a mesh vertex at `p` with normal `normal`, seen from
/// `eye`; `on` a lens triangle whose plane holds `p`, when known.
pub fn vertex_paths(
    lens: &Lens,
    eye: Vec3,
    (p, normal): (Vec3, Vec3),
    on: Option<u32>,
) -> TwoPaths {
    let dir = (p - eye).try_normalize().unwrap_or(Vec3::NEG_Z);
    two_paths(lens, &Lens::vertex_surface(p, normal, dir), dir, on)
}

/// Angle in degrees between two unit directions: 0 for equal, 180 for
/// non-finite input. `2·atan2(|a − b|, |a + b|)` keeps small angles exact
/// (acos of a dot product loses them to rounding).
pub fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    let angle = 2.0 * (a - b).length().atan2((a + b).length());
    if angle.is_nan() {
        180.0
    } else {
        angle.to_degrees()
    }
}

/// "More than `max_deg` apart" for unit directions: [`angle_deg`]`(a, b) >
/// max_deg` without the arctangent (the tessellation asks it of every edge
/// at every level). `2·atan2(|a − b|, |a + b|) > m ⟺ |a − b|² > tan²(m/2)·|a + b|²`
/// for m in [0°, 180°); non-finite directions are apart, as `angle_deg`
/// calls them 180°.
#[derive(Clone, Copy, Debug)]
pub struct AngleLimit {
    tan_half_sq: f32,
    max_deg: f32,
}

impl AngleLimit {
    pub fn new(max_deg: f32) -> Self {
        let half = (max_deg.clamp(0.0, 180.0) * 0.5).to_radians();
        Self {
            tan_half_sq: half.tan().powi(2),
            max_deg,
        }
    }

    pub fn exceeded(&self, a: Vec3, b: Vec3) -> bool {
        let (d, s) = ((a - b).length_squared(), (a + b).length_squared());
        if !(d.is_finite() && s.is_finite()) {
            return self.max_deg < 180.0;
        }
        d > self.tan_half_sq * s
    }
}
