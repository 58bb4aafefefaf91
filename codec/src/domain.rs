//! The signal domain the codec quantises in.
//!
//! * **Gamma compensation** (thesis §4.6): colour is coded as
//!   `γ(x) = sign(x)·|x|^(1/g)` so that errors in dark regions weigh more,
//!   and decoded with `γ⁻¹(y) = sign(y)·|y|^g` before the layers are summed
//!   linearly by the engine. The default `g = 2` makes the decoder's inverse
//!   one multiply per channel; `g` is stored in the container.
//! * **HDR**: values are never clipped. `γ` maps 1e-3..1e3 to 0.03..31.6, the
//!   quantiser works on floats with unbounded integer indices, and each
//!   image's quantiser step is chosen by the rate allocation relative to its
//!   own content (the per-image "range transform"). Negative inputs (inference
//!   ringing) survive through the sign-preserving γ.
//! * **Colour**: RGB → YCoCg after γ, decorrelating the channels. Alpha
//!   (coverage) stays linear.

/// Weights that turn squared YCoCg errors into squared RGB errors
/// (R = Y+Co−Cg, G = Y+Cg, B = Y−Co−Cg, errors independent), then alpha.
pub const CHANNEL_SSE_WEIGHT: [f64; 4] = [3.0, 2.0, 3.0, 1.0];

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gamma(pub f32);

impl Gamma {
    #[inline]
    pub fn forward(self, x: f32) -> f32 {
        if self.0 == 2.0 {
            x.signum() * x.abs().sqrt()
        } else {
            x.signum() * x.abs().powf(1.0 / self.0)
        }
    }
    #[inline]
    pub fn inverse(self, y: f32) -> f32 {
        if self.0 == 2.0 {
            y * y.abs()
        } else {
            y.signum() * y.abs().powf(self.0)
        }
    }
}

/// γ then YCoCg for one texel; `out` gets `channels` values.
#[inline]
pub fn to_domain(g: Gamma, rgba: &[f32], out: &mut [f32]) {
    let r = g.forward(rgba[0]);
    let gg = g.forward(rgba[1]);
    let b = g.forward(rgba[2]);
    out[0] = 0.25 * r + 0.5 * gg + 0.25 * b;
    out[1] = 0.5 * r - 0.5 * b;
    out[2] = -0.25 * r + 0.5 * gg - 0.25 * b;
    if rgba.len() > 3 && out.len() > 3 {
        out[3] = rgba[3];
    }
}

/// Inverse of [`to_domain`]; returns linear RGBA (alpha 1 when absent).
#[inline]
pub fn from_domain(g: Gamma, y: f32, co: f32, cg: f32, a: f32) -> [f32; 4] {
    let t = y - cg;
    [g.inverse(t + co), g.inverse(y + cg), g.inverse(t - co), a]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn domain_round_trip_hdr_and_negative() {
        for g in [Gamma(2.0), Gamma(2.2)] {
            for px in [[1e-3, 5.0, 1e3, 0.5], [-0.01, 0.0, 2.0, 1.0]] {
                let mut d = [0.0; 4];
                to_domain(g, &px, &mut d);
                let back = from_domain(g, d[0], d[1], d[2], d[3]);
                for c in 0..4 {
                    let tol = 1e-4 * px[c].abs().max(1e-3);
                    assert!((back[c] - px[c]).abs() <= tol, "{g:?} {px:?} -> {back:?}");
                }
            }
        }
    }
}
