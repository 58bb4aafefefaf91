//! Quantisation and binarisation of one image's DCT coefficients.
//!
//! Per 8×8 block, in raster order: a "coded" flag (context: how many of the
//! left/upper neighbours were coded); then, CABAC-style, for each zig-zag
//! position a significance flag and, after each nonzero, a "last" flag;
//! magnitudes as adaptive unary up to 15 then Exp-Golomb; signs raw. The DC
//! is predicted from the left (or upper) block's quantised DC, which is
//! what the smooth top pyramid levels need. Contexts are kept apart for
//! luma, chroma and alpha.

mod decode;
mod encode;
#[cfg(test)]
mod tests;

pub use decode::{AddToPlanes, BlockSink, decode_image, decode_image_add};
pub use encode::encode_image;

use crate::dct::{Dct8, NN, forward_plane};
use crate::domain::CHANNEL_SSE_WEIGHT;
use crate::entropy::Ctx;

const UNARY: usize = 15;
const EG_MAX_PREFIX: usize = 30;
/// Quantised magnitudes are clamped here so Exp-Golomb stays within its cap.
const MAX_MAG: u32 = 1 << 28;
/// Rounding offsets: plain rounding for DC, a dead zone for AC (RD-better
/// for Laplacian-distributed coefficients at low rates).
const ROUND_DC: f32 = 0.5;
const ROUND_AC: f32 = 1.0 / 3.0;

/// Quantiser step for a stored step index; 0 means "image not coded".
/// Quarter-octave steps spanning 2^-31.75 ..= 2^31.75.
pub fn step_of(idx: u8) -> f32 {
    (2.0f32).powf((idx as f32 - 128.0) / 4.0)
}

/// Smallest index whose step is ≥ `s` (saturating).
pub fn idx_at_least(s: f32) -> u8 {
    let i = (s.max(1e-30).log2() * 4.0 + 128.0).ceil();
    i.clamp(1.0, 255.0) as u8
}

#[derive(Clone)]
struct ClassCtx {
    coded: [Ctx; 3],
    sig: [Ctx; NN],
    last: [Ctx; NN],
    mag: [[Ctx; UNARY]; 2],
    eg: [Ctx; EG_MAX_PREFIX + 1],
}

impl Default for ClassCtx {
    fn default() -> Self {
        Self {
            coded: [Ctx::default(); 3],
            sig: [Ctx::default(); NN],
            last: [Ctx::default(); NN],
            mag: [[Ctx::default(); UNARY]; 2],
            eg: [Ctx::default(); EG_MAX_PREFIX + 1],
        }
    }
}

/// Adaptive state of one stream (shared by the images coded in it).
#[derive(Clone, Default)]
pub struct Contexts {
    class: [ClassCtx; 3],
}

fn class_of(channel: usize) -> usize {
    match channel {
        0 => 0,
        1 | 2 => 1,
        _ => 2,
    }
}

/// One plane's coefficients with per-block summaries for fast RD sweeps.
pub struct CoefPlane {
    coefs: Vec<f32>,
    ac_max: Vec<f32>,
    ac_energy: Vec<f64>,
}

/// One image (all channels of one face at one MIP) in the DCT domain.
pub struct CoefImage {
    pub w: usize,
    pub h: usize,
    planes: Vec<CoefPlane>,
}

impl CoefImage {
    /// `planar` holds `channels` planes of `w × h` back to back.
    pub fn new(dct: &mut Dct8, planar: &[f32], w: usize, h: usize, channels: usize) -> Self {
        let planes = (0..channels)
            .map(|c| {
                let coefs = forward_plane(dct, &planar[c * w * h..][..w * h], w, h);
                let (ac_max, ac_energy) = coefs
                    .chunks_exact(NN)
                    .map(|b| {
                        let ac = &b[1..];
                        (
                            ac.iter().fold(0.0f32, |m, v| m.max(v.abs())),
                            ac.iter().map(|&v| v as f64 * v as f64).sum::<f64>(),
                        )
                    })
                    .unzip();
                CoefPlane {
                    coefs,
                    ac_max,
                    ac_energy,
                }
            })
            .collect();
        Self { w, h, planes }
    }

    pub fn max_abs(&self) -> f32 {
        self.planes
            .iter()
            .flat_map(|p| p.coefs.iter())
            .fold(0.0f32, |m, v| m.max(v.abs()))
    }

    /// Weighted squared error of not coding the image at all.
    pub fn energy(&self) -> f64 {
        self.planes
            .iter()
            .enumerate()
            .map(|(c, p)| {
                CHANNEL_SSE_WEIGHT[c] * p.coefs.iter().map(|&v| v as f64 * v as f64).sum::<f64>()
            })
            .sum()
    }
}
