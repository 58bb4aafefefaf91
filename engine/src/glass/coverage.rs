//! Where an inner shell layer can matter: the cone of directions (from the
//! shell origin) its map covers, and the lens triangles whose lookups may
//! enter it. Only those are drawn reading every layer; the rest read the
//! outermost layer alone, so a near object costs the frame only where it
//! shows through the glass. Conservative up to the MIP level a fragment
//! reads: a triangle is left out only when no direction between its
//! vertices' lookups comes within [`MARGIN_LEVEL`]'s bilinear footprint
//! of a covered texel (coarser reads, at the lens's grazing edges, may
//! see a blurred trace of the layer there; measured in the README).

use glam::Vec3;
use half::f16;
use inference::glass::MAX_SHELLS;
use inference::glass::vertices::stride;
use rayon::prelude::*;

/// The MIP level whose bilinear footprint (two of its texels) the cone
/// is widened by.
pub const MARGIN_LEVEL: u32 = 3;

/// A cone of directions: unit axis and half angle (π covers every
/// direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    pub axis: Vec3,
    pub half_angle: f32,
}

impl Cone {
    /// Every direction.
    pub const ALL: Cone = Cone {
        axis: Vec3::Z,
        half_angle: std::f32::consts::PI,
    };

    /// No direction: a layer that covers nothing (negative half angle).
    pub const NONE: Cone = Cone {
        axis: Vec3::Z,
        half_angle: -1.0,
    };

    /// Whether the cone around unit `dir` whose half angle has cosine
    /// `cos_spread` meets this one: the angle between the axes is at most
    /// the sum of the half angles (compared by cosines, no `acos`).
    pub fn meets(&self, dir: Vec3, cos_spread: f32) -> bool {
        if self.half_angle < 0.0 {
            return false;
        }
        let cs = cos_spread.clamp(-1.0, 1.0);
        let (sh, ch) = self.half_angle.sin_cos();
        // The sum reaches π (every direction) when spread ≥ π − half.
        if cs <= -ch {
            return true;
        }
        let ss = (1.0 - cs * cs).sqrt();
        dir.dot(self.axis) >= ch * cs - sh * ss
    }
}

/// The cone holding every texel of level 0 of a layer map (f16 RGBA, face
/// after face of `size`² texels, Vulkan cube order, rows from the top)
/// whose alpha is above zero, each texel counted with its own angular
/// radius; None when no texel is covered.
pub fn covered_cone(bytes: &[u8], size: u32) -> Option<Cone> {
    let n = size as usize;
    let texels: &[f16] = bytemuck::try_cast_slice(bytes.get(..6 * n * n * 8)?).ok()?;
    let covered: Vec<Vec3> = (0..6 * n * n)
        .filter(|&i| texels[4 * i + 3].to_f32() > 0.0)
        .map(|i| texel_dir(i / (n * n), (i % (n * n)) % n, (i % (n * n)) / n, n))
        .collect();
    if covered.is_empty() {
        return None;
    }
    // A texel's directions lie within its half diagonal of its centre (at
    // most √2/size of the face's tangent plane), and a read at
    // MARGIN_LEVEL filters two of that level's texels further.
    let reach = 1.0 + 2.0 * (1u32 << MARGIN_LEVEL) as f32;
    let texel_radius = (reach * std::f32::consts::SQRT_2 / size as f32).atan();
    let axis = covered.iter().sum::<Vec3>().try_normalize();
    let Some(axis) = axis else {
        return Some(Cone::ALL);
    };
    let widest = covered
        .iter()
        .map(|d| d.dot(axis).clamp(-1.0, 1.0).acos())
        .fold(0.0f32, f32::max);
    Some(Cone {
        axis,
        half_angle: (widest + texel_radius).min(std::f32::consts::PI),
    })
}

/// Unit direction of texel (`x`, `y`) of `face` (`size`² per face).
fn texel_dir(face: usize, x: usize, y: usize, size: usize) -> Vec3 {
    let s = 2.0 * (x as f64 + 0.5) / size as f64 - 1.0;
    let t = 2.0 * (y as f64 + 0.5) / size as f64 - 1.0;
    let d = inference::solve::seams::cube_dir(face as u32, s, t);
    Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32).normalize()
}

/// `indices` (triangles of a layered stream with `MAX_SHELLS` lookups
/// per term) reordered so the triangles whose lookups into an inner shell
/// `i < cones.len()` may meet `cones[i]` come first; returns how many
/// indices those are.
pub fn split_triangles(
    stream: &[f32],
    indices: &[u32],
    cones: &[Cone],
    out: &mut Vec<u32>,
) -> usize {
    let stride = stride(MAX_SHELLS);
    let lookup = |v: u32, term: usize, shell: usize| -> Option<Vec3> {
        let at = v as usize * stride + 9 + 3 * (term * MAX_SHELLS + shell);
        stream.get(at..at + 3).map(Vec3::from_slice)
    };
    let needs_layers = |tri: &[u32]| -> bool {
        (0..2).any(|term| {
            cones.iter().enumerate().any(|(shell, cone)| {
                let mut looks = [Vec3::ZERO; 3];
                for (l, &v) in looks.iter_mut().zip(tri) {
                    match lookup(v, term, shell).and_then(Vec3::try_normalize) {
                        Some(d) => *l = d,
                        None => return true,
                    }
                }
                let Some(mid) = (looks[0] + looks[1] + looks[2]).try_normalize() else {
                    return true;
                };
                let cos_spread = looks.iter().map(|d| d.dot(mid)).fold(1.0f32, f32::min);
                cone.meets(mid, cos_spread)
            })
        })
    };
    let flags: Vec<bool> = indices.par_chunks_exact(3).map(needs_layers).collect();
    out.clear();
    out.reserve(indices.len());
    for pass in [true, false] {
        for (tri, &f) in indices.chunks_exact(3).zip(&flags) {
            if f == pass {
                out.extend_from_slice(tri);
            }
        }
    }
    3 * flags.iter().filter(|&&f| f).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stream of `looks.len()` vertices whose inner-shell lookups (both
    /// terms) are `looks`.
    fn stream(looks: &[Vec3]) -> Vec<f32> {
        let stride = stride(MAX_SHELLS);
        let mut s = vec![0.0; looks.len() * stride];
        for (v, l) in looks.iter().enumerate() {
            for term in 0..2 {
                let at = v * stride + 9 + 3 * (term * MAX_SHELLS);
                s[at..at + 3].copy_from_slice(&l.to_array());
            }
        }
        s
    }

    #[test]
    fn triangles_meeting_the_cone_come_first_and_none_is_lost() {
        let cone = Cone {
            axis: Vec3::X,
            half_angle: 10f32.to_radians(),
        };
        let (a, b) = (20f32.to_radians(), 5f32.to_radians());
        let looks = [
            // 0-2: all inside.
            Vec3::X,
            Vec3::new(1.0, 0.05, 0.0),
            Vec3::new(1.0, 0.0, 0.05),
            // 3-5: far away (−z).
            -Vec3::Z,
            Vec3::new(0.05, 0.0, -1.0),
            Vec3::new(0.0, 0.05, -1.0),
            // 6-8: every vertex outside, the triangle across the cone.
            Vec3::new(a.cos(), a.sin(), 0.0),
            Vec3::new(a.cos(), -a.sin(), 0.0),
            Vec3::new(b.cos(), 0.0, 3.0 * b.sin()),
        ];
        let s = stream(&looks);
        let indices = [3, 4, 5, 0, 1, 2, 6, 7, 8];
        let mut out = Vec::new();
        let n = split_triangles(&s, &indices, &[cone], &mut out);
        assert_eq!(n, 6);
        assert_eq!(out, vec![0, 1, 2, 6, 7, 8, 3, 4, 5]);
        // No cone: nothing needs layers; every direction: all do.
        assert_eq!(split_triangles(&s, &indices, &[], &mut out), 0);
        assert_eq!(split_triangles(&s, &indices, &[Cone::ALL], &mut out), 9);
        // A layer covering nothing needs no triangle, even the widest.
        assert_eq!(split_triangles(&s, &indices, &[Cone::NONE], &mut out), 0);
        assert!(
            !Cone::NONE.meets(Vec3::X, -1.0),
            "a spread over every direction"
        );
    }

    #[test]
    fn the_cone_holds_every_covered_texel() {
        let size = 8u32;
        let n = size as usize;
        let mut texels = vec![f16::ZERO; 6 * n * n * 4];
        // Face 0 (+x), a 2×2 block in its middle, and one texel beside it.
        for (x, y) in [(3, 3), (4, 3), (3, 4), (4, 4), (6, 4)] {
            texels[4 * (y * n + x) + 3] = f16::ONE;
        }
        let bytes: &[u8] = bytemuck::cast_slice(&texels);
        let cone = covered_cone(bytes, size).expect("covered");
        assert!(cone.axis.x > 0.95, "{cone:?}");
        for (x, y) in [(3, 3), (6, 4)] {
            assert!(cone.meets(texel_dir(0, x, y, n), 1.0));
        }
        assert!(!cone.meets(-Vec3::X, 1.0));
        // A wide enough cone around −x reaches it.
        assert!(cone.meets(-Vec3::X, -1.0));
        assert!(cone.half_angle < 2.0, "{cone:?}");
        assert_eq!(covered_cone(&vec![0u8; 6 * n * n * 8], size), None);
    }
}
