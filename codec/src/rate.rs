//! Rate allocation (thesis §4.5): equal-slope points on every image's
//! rate/distortion curve under one total budget.
//!
//! Every coded image (texture × block × pyramid level × node × face × MIP)
//! has an operational R-D curve measured by actually quantising and
//! entropy-coding it at a ladder of quantiser steps. Minimising
//! `Σ w·D + λ·R` picks, for one λ, the point of equal slope −λ on every
//! curve (on its convex hull); a 1D search on λ meets the budget.
//!
//! Weights make this the thesis's objective: an image at a pyramid node is
//! added into every leaf below it, so its squared error counts once per
//! leaf; a texture's error is its per-element MSE times its screen area
//! (`E_i = A_i · MSE_i`, "the sum of squared errors on the screen").
//! The cap `MSE_i ≤ α · mean MSE` is the thesis's second pass: textures over
//! the cap get their own smaller λ (more bits) and the rest is re-solved.

/// The error the rate allocation minimises under the byte budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// The thesis's on-screen error: each texture's per-element MSE times
    /// its screen area (`TextureInfo::screen_area`), whatever its size.
    Screen,
    /// The squared error summed over every element of every texture, the
    /// MSE that [`crate::quality`]'s pooled texture PSNR measures (screen
    /// areas ignored). Use with `alpha_cap: f64::INFINITY` for that PSNR's
    /// optimum: the cap rebalances textures against it.
    Texels,
}

/// One operational point: quantiser step index (0 = not coded), bits, and
/// RGB-weighted squared error in the coding domain.
#[derive(Clone, Copy, Debug)]
pub struct RdPoint {
    pub idx: u8,
    pub bits: f64,
    pub dist: f64,
}

/// The curve of one image and what its errors are worth.
#[derive(Clone, Debug)]
pub struct AtomRd {
    pub texture: usize,
    /// Valid leaves (parameter samples) this image is summed into.
    pub leaves: f64,
    /// `points[0]` is "not coded".
    pub points: Vec<RdPoint>,
}

/// Per-texture constants: screen area and elements per texture.
#[derive(Clone, Copy, Debug)]
pub struct TexWeight {
    pub area: f64,
    pub elements: f64,
}

#[derive(Clone, Debug)]
pub struct Allocation {
    /// Chosen index into each atom's `points`.
    pub choice: Vec<usize>,
    pub lambda: f64,
    /// Per-texture λ caps from the α pass (∞ where uncapped).
    pub caps: Vec<f64>,
    pub bits: f64,
    /// Per-texture coding-domain MSE (per element) predicted by the curves.
    pub mse: Vec<f64>,
}

fn pick(a: &AtomRd, w: &[TexWeight], lambda: f64) -> usize {
    let tw = &w[a.texture];
    let wt = tw.area * a.leaves / tw.elements;
    let mut best = 0;
    let mut best_j = f64::INFINITY;
    for (k, p) in a.points.iter().enumerate() {
        let j = wt * p.dist + lambda * p.bits;
        if j < best_j {
            best_j = j;
            best = k;
        }
    }
    best
}

fn eval(atoms: &[AtomRd], w: &[TexWeight], lambda: f64, caps: &[f64]) -> (Vec<usize>, f64) {
    let choice: Vec<usize> = atoms
        .iter()
        .map(|a| pick(a, w, lambda.min(caps[a.texture])))
        .collect();
    let bits = atoms
        .iter()
        .zip(&choice)
        .map(|(a, &c)| a.points[c].bits)
        .sum();
    (choice, bits)
}

fn texture_mse(atoms: &[AtomRd], w: &[TexWeight], choice: &[usize]) -> Vec<f64> {
    let mut mse = vec![0.0; w.len()];
    for (a, &c) in atoms.iter().zip(choice) {
        mse[a.texture] += a.leaves * a.points[c].dist / w[a.texture].elements;
    }
    mse
}

const LO: f64 = -60.0;
const HI: f64 = 60.0;

/// Smallest λ (log-bisection) whose allocation fits `budget_bits`.
fn solve(
    atoms: &[AtomRd],
    w: &[TexWeight],
    budget_bits: f64,
    caps: &[f64],
) -> (f64, Vec<usize>, f64) {
    let (mut lo, mut hi) = (LO, HI);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        let (_, bits) = eval(atoms, w, 10f64.powf(mid), caps);
        if bits <= budget_bits {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let lambda = 10f64.powf(hi);
    let (choice, bits) = eval(atoms, w, lambda, caps);
    (lambda, choice, bits)
}

/// Largest λ for texture `t` alone whose MSE stays within `limit`.
fn cap_for(atoms: &[AtomRd], w: &[TexWeight], t: usize, limit: f64) -> f64 {
    let mine: Vec<AtomRd> = atoms.iter().filter(|a| a.texture == t).cloned().collect();
    let none = vec![f64::INFINITY; w.len()];
    let (mut lo, mut hi) = (LO, HI);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        let (choice, _) = eval(&mine, w, 10f64.powf(mid), &none);
        if texture_mse(&mine, w, &choice)[t] <= limit {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    10f64.powf(lo)
}

/// Allocates `budget_bits` over all atoms; `alpha` is the MSE cap factor
/// (∞ disables the second pass).
pub fn allocate(atoms: &[AtomRd], w: &[TexWeight], budget_bits: f64, alpha: f64) -> Allocation {
    let mut caps = vec![f64::INFINITY; w.len()];
    let (mut lambda, mut choice, mut bits) = solve(atoms, w, budget_bits, &caps);
    if alpha.is_finite() && w.len() > 1 {
        let n = w.len() as f64;
        let mut capped = vec![false; w.len()];
        for _ in 0..12 {
            let mse = texture_mse(atoms, w, &choice);
            let mean = mse.iter().sum::<f64>() / n;
            let over: Vec<usize> = (0..w.len())
                .filter(|&t| mse[t] > alpha * mean * (1.0 + 1e-3))
                .collect();
            if over.is_empty() {
                break;
            }
            over.iter().for_each(|&t| capped[t] = true);
            // Fixed point of M = α·mean when the capped textures sit at M:
            // M = α·Σ(uncapped MSE) / (n − α·|capped|).
            let k = capped.iter().filter(|&&c| c).count() as f64;
            let rest: f64 = (0..w.len()).filter(|&t| !capped[t]).map(|t| mse[t]).sum();
            let limit = if n - alpha * k > 0.0 {
                alpha * rest / (n - alpha * k)
            } else {
                alpha * mean
            };
            for t in (0..w.len()).filter(|&t| capped[t]) {
                caps[t] = cap_for(atoms, w, t, limit);
            }
            if std::env::var_os("CODEC_DEBUG_RATE").is_some() {
                eprintln!("alpha pass: mse {mse:?} limit {limit} caps {caps:?} lambda {lambda}");
            }
            // Caps the budget cannot afford are relaxed until it can.
            loop {
                (lambda, choice, bits) = solve(atoms, w, budget_bits, &caps);
                if bits <= budget_bits || caps.iter().all(|c| !c.is_finite()) {
                    break;
                }
                caps.iter_mut()
                    .filter(|c| c.is_finite())
                    .for_each(|c| *c *= 2.0);
                if caps.iter().all(|&c| c > 10f64.powf(HI)) {
                    caps.iter_mut().for_each(|c| *c = f64::INFINITY);
                }
            }
        }
    }
    let mse = texture_mse(atoms, w, &choice);
    Allocation {
        choice,
        lambda,
        caps,
        bits,
        mse,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(texture: usize, scale: f64) -> AtomRd {
        // D(R) = scale · 2^(-R/4), sampled.
        let points = (0..20)
            .map(|k| RdPoint {
                idx: k as u8,
                bits: 8.0 * k as f64,
                dist: scale * 2f64.powf(-2.0 * k as f64),
            })
            .collect();
        AtomRd {
            texture,
            leaves: 1.0,
            points,
        }
    }

    #[test]
    fn budget_is_met_and_slopes_equalise() {
        let atoms = vec![curve(0, 1.0), curve(0, 100.0)];
        let w = [TexWeight {
            area: 1.0,
            elements: 1.0,
        }];
        let a = allocate(&atoms, &w, 80.0, f64::INFINITY);
        assert!(a.bits <= 80.0);
        // Higher-energy image gets more bits.
        assert!(a.choice[1] > a.choice[0], "{:?}", a.choice);
    }

    #[test]
    fn alpha_cap_limits_the_worst_texture() {
        // Texture 1 has tiny screen area, so without a cap it gets starved.
        let atoms = vec![curve(0, 100.0), curve(1, 100.0)];
        let w = [
            TexWeight {
                area: 1000.0,
                elements: 1.0,
            },
            TexWeight {
                area: 1.0,
                elements: 1.0,
            },
        ];
        let free = allocate(&atoms, &w, 96.0, f64::INFINITY);
        let mean = |m: &[f64]| m.iter().sum::<f64>() / m.len() as f64;
        assert!(free.mse[1] > 1.25 * mean(&free.mse));
        let capped = allocate(&atoms, &w, 96.0, 1.25);
        assert!(capped.bits <= 96.0);
        assert!(
            capped.mse[1] <= 1.25 * mean(&capped.mse) * 1.0001,
            "{:?}",
            capped.mse
        );
    }
}
