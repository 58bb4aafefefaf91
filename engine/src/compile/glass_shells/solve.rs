//! The thesis's shell solve (§6.3.3): the traced frame itself, both terms
//! at once. Row p, channel c: `w_T,c(p)·A_T[p] + w_R,c(p)·A_R[p]` against
//! the traced frame's pixel, over the pixels the lens covers wholly; `A_T`,
//! `A_R` the probe-rendered matrices of the two terms' lookups, `w` the
//! traced mean `F·G` of each term at the pixel; each row weighted by the
//! pixel's √confidence (thesis §6.3.3, θ_c = 5°).

use std::collections::HashMap;

use crate::probe::VulkanProbe;
use anyhow::{Context, Result};
use inference::glass::targets::GlassTargets;
use inference::probe::{ProbeGeometry, build_matrix};
use inference::solve::csr::{CsrBuilder, CsrMatrix};
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::solve::{SolveOptions, solve_channels};

/// One view: the two terms' probe geometry, the targets (weights,
/// coverage) and an independently traced frame (RGB per pixel).
pub struct FrameView {
    pub t: ProbeGeometry,
    pub r: ProbeGeometry,
    pub targets: GlassTargets,
    pub beauty: Vec<[f32; 3]>,
}

/// What one channel's solve did.
#[derive(Clone, Copy, Debug)]
pub struct ChannelStats {
    pub rows: usize,
    pub iterations: u32,
    pub relative_residual: f32,
}

/// Row `row` of `a` scaled by `s`, appended to `entries`.
pub(super) fn extend_scaled_row(entries: &mut Vec<(u32, f32)>, a: &CsrMatrix, row: usize, s: f32) {
    let span = a.row_ptr[row]..a.row_ptr[row + 1];
    entries.extend(
        a.col_idx[span.clone()]
            .iter()
            .zip(&a.values[span])
            .map(|(&c, &v)| (c, s * v)),
    );
}

/// √confidence of a pixel's row: the two terms' confidences
/// (`1 − min(θ_m², θ_c²)/θ_c²`, θ_m the widest angle between the pixel's
/// exit rays) weighted by each term's share `F·G` of the pixel, so a
/// pixel whose one lookup per term stands for a wide spread of exit rays
/// pulls the map less.
pub(super) fn row_weight((wt, ct): (f32, f32), (wr, cr): (f32, f32)) -> f32 {
    let share = wt.abs() + wr.abs();
    match share > 0.0 {
        true => ((wt.abs() * ct + wr.abs() * cr) / share)
            .clamp(0.0, 1.0)
            .sqrt(),
        false => 0.0,
    }
}

/// Per channel, the combined rows of every view and their targets.
fn system(
    probe: &mut VulkanProbe,
    views: &[FrameView],
    layout: &TextureLayout,
    shape: TextureShape,
) -> Result<(Vec<CsrMatrix>, Vec<Vec<f32>>)> {
    let mut a: Vec<CsrBuilder> = (0..3).map(|_| CsrBuilder::new(layout.len())).collect();
    let mut b: Vec<Vec<f32>> = vec![Vec::new(); 3];
    let mut entries = Vec::new();
    for v in views {
        let at = build_matrix(probe, &v.t, layout, shape, &mut |_, _| {})?;
        let ar = build_matrix(probe, &v.r, layout, shape, &mut |_, _| {})?;
        let rows_r: HashMap<u32, usize> =
            ar.pixels.iter().enumerate().map(|(i, &p)| (p, i)).collect();
        for (i, &p) in at.pixels.iter().enumerate() {
            let pu = p as usize;
            let (Some(&j), Some(&cov)) = (rows_r.get(&p), v.targets.coverage.get(pu)) else {
                continue;
            };
            let (Some(&wt), Some(&wr), Some(px)) = (
                v.targets.t.weight.get(pu),
                v.targets.r.weight.get(pu),
                v.beauty.get(pu),
            ) else {
                continue;
            };
            if cov < 1.0 {
                continue;
            }
            let confidence = [&v.targets.t, &v.targets.r].map(|term| term.confidence.get(pu));
            let [Some(&ct), Some(&cr)] = confidence else {
                continue;
            };
            for c in 0..3 {
                let s = row_weight((wt[c], ct), (wr[c], cr));
                if s == 0.0 {
                    continue;
                }
                entries.clear();
                extend_scaled_row(&mut entries, &at.a, i, s * wt[c]);
                extend_scaled_row(&mut entries, &ar.a, j, s * wr[c]);
                a[c].push_row(&entries)?;
                b[c].push(s * px[c]);
            }
        }
    }
    Ok((a.into_iter().map(CsrBuilder::finish).collect(), b))
}

/// `b − A x`.
pub(super) fn residual(a: &CsrMatrix, x: &[f32], b: &[f32]) -> Vec<f32> {
    let mut ax = vec![0.0; a.rows];
    a.mul(x, &mut ax);
    b.iter().zip(&ax).map(|(b, ax)| b - ax).collect()
}

/// The shell map (per channel, layout order) fitted to the views' frames.
/// With `refine`, a correction to `traced` is solved instead (each frame
/// less the traced map's rendering, a prior `refine`·‖δ‖² on the
/// correction, so texels no view sees keep the traced values); otherwise
/// each channel's solve starts from `traced`.
pub fn solve_frames(
    probe: &mut VulkanProbe,
    views: &[FrameView],
    shape: TextureShape,
    traced: &[Vec<f32>],
    refine: Option<f32>,
) -> Result<(Vec<Vec<f32>>, Vec<ChannelStats>)> {
    let layout = TextureLayout::full_chain(shape);
    let (a, b) = system(probe, views, &layout, shape)?;
    let options = SolveOptions {
        eps_prior: refine.unwrap_or(0.0),
        ..SolveOptions::default()
    };
    let (mut map, mut stats) = (Vec::new(), Vec::new());
    for c in 0..3 {
        let (rhs, x0) = match refine {
            Some(_) => (residual(&a[c], &traced[c], &b[c]), None),
            None => (b[c].clone(), Some([traced[c].as_slice()])),
        };
        let s = solve_channels(
            &a[c],
            &[rhs.as_slice()],
            &layout,
            x0.as_ref().map(|x| &x[..]),
            &options,
        )?;
        let x = s
            .into_iter()
            .next()
            .context("the solve returned no channel")?;
        stats.push(ChannelStats {
            rows: a[c].rows,
            iterations: x.iterations,
            relative_residual: x.relative_residual,
        });
        map.push(match refine {
            Some(_) => traced[c].iter().zip(&x.x).map(|(t, d)| t + d).collect(),
            None => x.x,
        });
    }
    Ok((map, stats))
}

#[cfg(test)]
mod tests {
    use super::row_weight;

    #[test]
    fn row_weight_follows_the_larger_terms_confidence() {
        assert_eq!(row_weight((1.0, 1.0), (0.0, 0.0)), 1.0);
        assert_eq!(row_weight((0.0, 0.0), (0.0, 0.0)), 0.0, "no light, no row");
        // Transmission carries 0.9 of the pixel but its rays spread wide.
        let w = row_weight((0.9, 0.0), (0.1, 1.0));
        assert!((w - 0.1f32.sqrt()).abs() < 1e-6, "{w}");
        // A confident pixel outweighs an unsure one, whatever the scale.
        assert!(row_weight((2.0, 0.8), (0.2, 0.8)) > row_weight((0.5, 0.2), (0.05, 0.2)));
        assert!(row_weight((1.0, 1.5), (0.0, 0.0)) <= 1.0, "clamped");
    }
}
