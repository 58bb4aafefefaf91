//! Ray geometry and Fresnel shared by camera paths and photon paths: offsets off a
//! surface, reflection and refraction directions, the glossy lobe's exponent.

use glam::Vec3;

use crate::fresnel::schlick_fresnel;

/// Offset along the normal that clears f32 rounding at `p`'s magnitude (metre-scale scenes).
pub(crate) fn offset(p: Vec3, n: Vec3) -> Vec3 {
    p + n * (1e-4 * p.abs().max_element().max(1.0))
}

pub(crate) fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Keeps a direction drawn around a shading normal above the geometric surface.
pub(super) fn above(dir: Vec3, ng: Vec3) -> Vec3 {
    let c = dir.dot(ng);
    if c > 1e-6 {
        dir
    } else {
        (dir - 2.0 * c * ng).normalize_or(ng)
    }
}

/// Phong exponent equivalent to roughness `r` (Beckmann α = r²), kept in a finite range.
pub fn phong_exponent(roughness: f32) -> f32 {
    let a = (roughness * roughness).clamp(1e-3, 1.0);
    (2.0 / (a * a) - 2.0).clamp(1.0, 1e6)
}

/// Dielectric Fresnel for a ray hitting from the `front` side: `(F, cos_t)`, F = 1 under
/// total internal reflection, 0 at IOR 1 (no interface). Uses the runtime's Schlick formula.
pub(crate) fn dielectric(ior: f32, cos_i: f32, front: bool) -> (f32, Option<f32>) {
    let ior = if ior.is_finite() && ior > 0.0 {
        ior
    } else {
        1.0
    };
    if ior == 1.0 {
        // No optical interface: Schlick's grazing term would still reflect.
        return (0.0, Some(cos_i));
    }
    let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
    let eta = if front { 1.0 / ior } else { ior };
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, None);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // Schlick is defined on the rarer side's angle.
    let c = if eta > 1.0 { cos_t } else { cos_i };
    (schlick_fresnel(Vec3::splat(f0), c).x, Some(cos_t))
}

#[cfg(test)]
pub(crate) fn dielectric_for_tests(ior: f32, cos_i: f32, front: bool) -> (f32, Option<f32>) {
    dielectric(ior, cos_i, front)
}

/// Refracted direction through a surface with shading normal `n` (facing the incoming ray).
pub(crate) fn refract(d: Vec3, n: Vec3, ior: f32, front: bool, cos_i: f32, cos_t: f32) -> Vec3 {
    let eta = if front { 1.0 / ior } else { ior };
    (eta * d + (eta * cos_i - cos_t) * n).normalize_or(-n)
}
