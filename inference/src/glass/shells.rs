//! Environment shells (thesis §6.3): simple surfaces standing in for the
//! geometry around the lens, each with a cube map indexed by where an exit
//! ray meets it, `hit − origin` (the lens centroid, shared by all shells).
//! Spheres and cylinders for surroundings, quads for sparse nearby objects
//! (§6.3.2.1), and the room's own box when a shell holds the room.
//!
//! Every lookup is finite for finite input: a ray that misses its shell
//! (starts outside it and points away) falls back to its direction, i.e. to
//! a shell at infinity.

use glam::{Vec3, Vec3A};

use crate::em_geometry::EmGeometry;

/// Shells one lens may have (the playback shader binds two samples' maps
/// of each).
pub const MAX_SHELLS: usize = 3;

/// A shell's surface.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ShellShape {
    /// Centred at the shells' origin.
    Sphere { radius: f32 },
    /// Vertical axis through the origin, closed by caps at `origin.y ± half_height`.
    Cylinder { radius: f32, half_height: f32 },
    /// A rectangle: centre, unit normal (facing the origin's side), unit
    /// in-plane axes `u`, `v` and half extents along them.
    Quad {
        center: [f32; 3],
        normal: [f32; 3],
        u: [f32; 3],
        half: [f32; 2],
    },
    /// Axis-aligned box (the room).
    Box { min: [f32; 3], max: [f32; 3] },
    /// At infinity: the lookup is the exit direction (a static EM).
    Infinity,
}

/// A quad's far fallback: rays that cannot reach its plane slide along it
/// this many half extents away (thesis §6.3.2.1).
const QUAD_FAR: f32 = 1e3;

impl ShellShape {
    /// The point where the ray from `p` along unit `d` meets the shell
    /// (leaving it from inside, entering from outside); None on a miss.
    pub fn hit(&self, origin: Vec3, p: Vec3, d: Vec3) -> Option<Vec3> {
        match *self {
            ShellShape::Sphere { radius } => EmGeometry::Ellipsoid {
                center: origin,
                radii: Vec3::splat(radius),
            }
            .hit_distance(Vec3A::from(p), Vec3A::from(d))
            .map(|t| p + d * t),
            ShellShape::Box { min, max } => EmGeometry::Box {
                min: min.into(),
                max: max.into(),
            }
            .hit_distance(Vec3A::from(p), Vec3A::from(d))
            .map(|t| p + d * t),
            ShellShape::Cylinder {
                radius,
                half_height,
            } => cylinder_hit(origin, radius, half_height, p, d),
            ShellShape::Quad {
                center,
                normal,
                u,
                half,
            } => Some(quad_hit(center.into(), normal.into(), u.into(), half, p, d)),
            ShellShape::Infinity => None,
        }
    }

    /// The cube lookup of the ray: `hit − origin`, or `d` on a miss.
    pub fn lookup(&self, origin: Vec3, p: Vec3, d: Vec3) -> Vec3 {
        match self.hit(origin, p, d) {
            Some(h) if (h - origin).length_squared() > 1e-20 && h.is_finite() => h - origin,
            _ if d.is_finite() && d != Vec3::ZERO => d,
            _ => Vec3::Z,
        }
    }
}

/// Closed vertical cylinder around `origin`: the side or a cap. The shape
/// is convex, so from inside or outside the hit is the nearest crossing.
fn cylinder_hit(origin: Vec3, radius: f32, half: f32, p: Vec3, d: Vec3) -> Option<Vec3> {
    let q = p - origin;
    let mut best: Option<f32> = None;
    let mut consider = |t: f32, on_surface: bool| {
        if on_surface && t.is_finite() && t > 0.0 {
            best = Some(best.map_or(t, |b: f32| b.min(t)));
        }
    };
    // Side: (qx + t dx)² + (qz + t dz)² = r².
    let a = d.x * d.x + d.z * d.z;
    if a > 1e-12 {
        let b = q.x * d.x + q.z * d.z;
        let c = q.x * q.x + q.z * q.z - radius * radius;
        let disc = b * b - a * c;
        if disc >= 0.0 {
            let s = disc.sqrt();
            for t in [(-b - s) / a, (-b + s) / a] {
                let y = q.y + t * d.y;
                consider(t, y.abs() <= half);
            }
        }
    }
    // Caps.
    if d.y.abs() > 1e-12 {
        for y in [half, -half] {
            let t = (y - q.y) / d.y;
            let x = q.x + t * d.x;
            let z = q.z + t * d.z;
            consider(t, x * x + z * z <= radius * radius);
        }
    }
    best.map(|t| p + d * t)
}

/// Where the ray meets the quad's plane (anywhere on it: the cube lookup
/// takes any point); rays that never reach the plane slide along it, far
/// away in their tangential direction (thesis §6.3.2.1).
fn quad_hit(center: Vec3, normal: Vec3, u: Vec3, half: [f32; 2], p: Vec3, d: Vec3) -> Vec3 {
    let n = normal.normalize_or(Vec3::Z);
    let denom = d.dot(n);
    let t = (center - p).dot(n) / denom;
    if denom.abs() > 1e-6 && t.is_finite() && t > 0.0 {
        return p + d * t;
    }
    let tangent = (d - n * d.dot(n)).normalize_or(u.normalize_or(Vec3::X));
    center + tangent * (QUAD_FAR * half[0].max(half[1]).max(1e-3))
}

/// A placed shell: its shape and whether it is the outermost (opaque RGB;
/// inner shells carry coverage in alpha and composite "over").
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Shell {
    pub shape: ShellShape,
    /// Objects (scene indices) whose hits this shell stands for.
    pub objects: Vec<u32>,
    /// Mean distance of its hits from the origin (metres), for reports.
    pub distance: f32,
}

/// The shells around one lens, nearest first, sharing one origin.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShellSet {
    pub origin: [f32; 3],
    pub shells: Vec<Shell>,
}

impl ShellSet {
    pub fn origin(&self) -> Vec3 {
        self.origin.into()
    }

    /// Channels of shell `i`'s map: RGB for the outermost, RGBA inside.
    pub fn channels(&self, i: usize) -> usize {
        if i + 1 == self.shells.len() { 3 } else { 4 }
    }

    /// The lookups of the exit ray `(p, d)` into every shell, nearest first.
    pub fn lookups(&self, p: Vec3, d: Vec3, out: &mut [Vec3]) {
        let o = self.origin();
        for (shell, l) in self.shells.iter().zip(out.iter_mut()) {
            *l = shell.shape.lookup(o, p, d);
        }
    }
}
