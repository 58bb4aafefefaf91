//! The layered shells' solve. An inner layer's map is fitted to what the
//! views' exit rays see on it (the traced targets' per-shell images,
//! premultiplied RGBA), one row per covered pixel and term, as the
//! teapot's local layer is solved against its own traced image. The
//! outermost layer's is fitted to the whole frame, as the one room shell's
//! is (`solve.rs`), seen through the nearer layers as the targets trace
//! them: fitted to its own images instead it lost 0.3 dB over the glass
//! on the plane (README, *Per-sample layer maps*).

use super::solve::{extend_scaled_row, residual, row_weight};
use super::views::LayerView;
use crate::probe::VulkanProbe;
use anyhow::{Context, Result, bail};
use inference::glass::targets::TermImages;
use inference::probe::build_matrix;
use inference::solve::csr::{CsrBuilder, CsrMatrix};
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::solve::{SolveOptions, solve_channels};
use std::collections::HashMap;

/// √confidence of a term's row times the term's mean `F·G`: the frame
/// shows a layer's error scaled by the weight of the path that reads it,
/// and a pixel whose exit rays spread wide pulls the map less.
pub fn term_row_weight(weight: [f32; 3], confidence: f32) -> f32 {
    let w = weight.iter().map(|w| w.abs()).sum::<f32>() / 3.0;
    let s = confidence.clamp(0.0, 1.0).sqrt() * w;
    if s.is_finite() { s } else { 0.0 }
}

/// Layer `k`'s map (per channel, layout order: RGB or RGBA as `traced`
/// has channels) fitted to the views' layer-`k` images: a correction to
/// `traced` under the prior `refine`·‖δ‖², so texels no view sees keep
/// the traced values.
pub fn solve_layer(
    probe: &mut VulkanProbe,
    views: &[LayerView],
    k: usize,
    shape: TextureShape,
    traced: &[Vec<f32>],
    refine: f32,
) -> Result<Vec<Vec<f32>>> {
    let layout = TextureLayout::full_chain(shape);
    let channels = traced.len();
    let texels: Vec<usize> = traced.iter().map(Vec::len).collect();
    if !(1..=4).contains(&channels) || texels.iter().any(|&n| n != layout.len()) {
        bail!(
            "layer {k}: traced map of {channels} channels of {texels:?} texels, expected 1 to 4 of {}",
            layout.len()
        );
    }
    let mut a = CsrBuilder::new(layout.len());
    let mut b: Vec<Vec<f32>> = vec![Vec::new(); channels];
    let mut entries = Vec::new();
    for v in views {
        let Some(geometry) = v.shells.get(k) else {
            bail!("layer {k}: a view without that layer's geometry");
        };
        for (term, g) in [&v.targets.t, &v.targets.r].into_iter().zip(geometry) {
            let m = build_matrix(probe, g, &layout, shape, &mut |_, _| {})?;
            for (i, &p) in m.pixels.iter().enumerate() {
                let Some((s, image)) = row(term, &v.targets.coverage, k, p as usize) else {
                    continue;
                };
                entries.clear();
                extend_scaled_row(&mut entries, &m.a, i, s);
                a.push_row(&entries)?;
                for (c, b) in b.iter_mut().enumerate() {
                    b.push(s * image[c]);
                }
            }
        }
    }
    refined(&a.finish(), traced, &b, &layout, refine)
        .with_context(|| format!("solving shell layer {k}"))
}

/// `traced` (per channel) plus the correction δ minimising
/// `‖A(traced + δ) − b‖² + refine·‖δ‖²` for every channel's `b` at once.
fn refined(
    a: &CsrMatrix,
    traced: &[Vec<f32>],
    b: &[Vec<f32>],
    layout: &TextureLayout,
    refine: f32,
) -> Result<Vec<Vec<f32>>> {
    let rhs: Vec<Vec<f32>> = (traced.iter().zip(b))
        .map(|(t, b)| residual(a, t, b))
        .collect();
    let rhs: Vec<&[f32]> = rhs.iter().map(Vec::as_slice).collect();
    let options = SolveOptions {
        eps_prior: refine,
        ..SolveOptions::default()
    };
    let solved = solve_channels(a, &rhs, layout, None, &options)?;
    Ok(traced
        .iter()
        .zip(solved)
        .map(|(t, d)| t.iter().zip(&d.x).map(|(t, d)| t + d).collect())
        .collect())
}

/// The outermost layer's map (RGB per channel, layout order) fitted to
/// the views' whole frames: row p, channel c, both terms at once —
/// `Σ w_c·T·A[p]` against `beauty_c − Σ w_c·C_c`, where each term's nearer
/// layers add `C` and let `T` through (its targets' inner images
/// composited front to back) — each row weighted by the pixel's
/// √confidence; a correction to `traced` under the prior `refine`·‖δ‖².
pub fn solve_outer(
    probe: &mut VulkanProbe,
    views: &[LayerView],
    shape: TextureShape,
    traced: &[Vec<f32>],
    refine: f32,
) -> Result<Vec<Vec<f32>>> {
    let layout = TextureLayout::full_chain(shape);
    let texels: Vec<usize> = traced.iter().map(Vec::len).collect();
    if texels.len() != 3 || texels.iter().any(|&n| n != layout.len()) {
        bail!(
            "the outermost layer's traced map: {texels:?} texels per channel, expected RGB of {}",
            layout.len()
        );
    }
    let mut a: Vec<CsrBuilder> = (0..3).map(|_| CsrBuilder::new(layout.len())).collect();
    let mut b: Vec<Vec<f32>> = vec![Vec::new(); 3];
    let mut entries = Vec::new();
    for v in views {
        let k = v
            .shells
            .len()
            .checked_sub(1)
            .context("a view without layers")?;
        let [gt, gr] = &v.shells[k];
        let at = build_matrix(probe, gt, &layout, shape, &mut |_, _| {})?;
        let ar = build_matrix(probe, gr, &layout, shape, &mut |_, _| {})?;
        let rows_r: HashMap<u32, usize> =
            ar.pixels.iter().enumerate().map(|(i, &p)| (p, i)).collect();
        for (i, &p) in at.pixels.iter().enumerate() {
            let Some(&j) = rows_r.get(&p) else {
                continue;
            };
            let Some(px) = FramePixel::at(v, p as usize, k) else {
                continue;
            };
            for c in 0..3 {
                let s = row_weight((px.wt[c], px.ct), (px.wr[c], px.cr));
                if s <= 0.0 {
                    continue;
                }
                let (wt, wr) = (px.wt[c] * px.t.1, px.wr[c] * px.r.1);
                let front = px.wt[c] * px.t.0[c] + px.wr[c] * px.r.0[c];
                entries.clear();
                extend_scaled_row(&mut entries, &at.a, i, s * wt);
                extend_scaled_row(&mut entries, &ar.a, j, s * wr);
                a[c].push_row(&entries)?;
                b[c].push(s * (px.beauty[c] - front));
            }
        }
    }
    // Each channel has its own rows (weighted by its F·G): one solve each.
    (a.into_iter().map(CsrBuilder::finish).zip(traced).zip(b))
        .map(|((a, traced), b)| {
            let x = refined(&a, std::slice::from_ref(traced), &[b], &layout, refine)
                .context("solving the outermost shell layer")?;
            x.into_iter()
                .next()
                .context("the solve returned no channel")
        })
        .collect()
}

/// What a whole-frame row of the outermost layer reads at one pixel.
struct FramePixel {
    beauty: [f32; 3],
    wt: [f32; 3],
    wr: [f32; 3],
    ct: f32,
    cr: f32,
    /// Per term, what the nearer layers add and let through.
    t: ([f32; 3], f32),
    r: ([f32; 3], f32),
}

impl FramePixel {
    /// Pixel `p` of view `v` below `inner` nearer layers; None where the
    /// lens does not cover it wholly or a value is missing or not finite.
    fn at(v: &LayerView, p: usize, inner: usize) -> Option<FramePixel> {
        let g = &v.targets;
        if g.coverage.get(p).is_none_or(|&c| c < 1.0) {
            return None;
        }
        let px = FramePixel {
            beauty: *v.beauty.get(p)?,
            wt: *g.t.weight.get(p)?,
            wr: *g.r.weight.get(p)?,
            ct: *g.t.confidence.get(p)?,
            cr: *g.r.confidence.get(p)?,
            t: through(&g.t, p, inner)?,
            r: through(&g.r, p, inner)?,
        };
        let values = [px.beauty, px.wt, px.wr, px.t.0, px.r.0]
            .into_iter()
            .flatten();
        let finite = values
            .chain([px.ct, px.cr, px.t.1, px.r.1])
            .all(f32::is_finite);
        finite.then_some(px)
    }
}

/// What the first `inner` layers of `term`'s images at pixel `p` add
/// (premultiplied RGB) and let through, composited front to back.
fn through(term: &TermImages, p: usize, inner: usize) -> Option<([f32; 3], f32)> {
    let mut add = [0.0f32; 3];
    let mut pass = 1.0f32;
    for shell in term.shells.get(..inner)? {
        let [r, g, b, a] = *shell.get(p)?;
        for (sum, x) in add.iter_mut().zip([r, g, b]) {
            *sum += pass * x;
        }
        pass *= 1.0 - a.clamp(0.0, 1.0);
    }
    Some((add, pass))
}

/// Pixel `p`'s row weight and layer-`k` image for `term`: None where the
/// lens does not cover the pixel wholly or the row would weigh nothing.
fn row(term: &TermImages, coverage: &[f32], k: usize, p: usize) -> Option<(f32, [f32; 4])> {
    if coverage.get(p).is_none_or(|&c| c < 1.0) {
        return None;
    }
    let s = term_row_weight(*term.weight.get(p)?, *term.confidence.get(p)?);
    let image = *term.shells.get(k)?.get(p)?;
    (s > 0.0 && image.iter().all(|x| x.is_finite())).then_some((s, image))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_weigh_by_the_terms_share_and_confidence() {
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        assert!(close(term_row_weight([0.3, 0.6, 0.9], 1.0), 0.6));
        assert!(close(term_row_weight([-0.3, 0.6, 0.9], 0.25), 0.3));
        assert_eq!(term_row_weight([0.0; 3], 1.0), 0.0, "no light, no row");
        assert_eq!(
            term_row_weight([1.0; 3], -1.0),
            0.0,
            "no confidence, no row"
        );
        assert_eq!(term_row_weight([f32::NAN; 3], 1.0), 0.0);
        let term = TermImages {
            shells: vec![vec![[0.5, 0.5, 0.5, 1.0]; 2], vec![[1.0; 4], [f32::NAN; 4]]],
            confidence: vec![1.0, 1.0],
            weight: vec![[0.5; 3], [0.5; 3]],
        };
        assert_eq!(
            row(&term, &[1.0, 1.0], 0, 0),
            Some((0.5, [0.5, 0.5, 0.5, 1.0]))
        );
        assert_eq!(row(&term, &[0.9, 1.0], 0, 0), None, "an edge pixel");
        assert_eq!(row(&term, &[1.0, 1.0], 1, 1), None, "a non-finite target");
        assert_eq!(row(&term, &[1.0, 1.0], 2, 0), None, "no such layer");
    }

    #[test]
    fn nearer_layers_add_front_to_back_and_let_the_rest_through() {
        let term = TermImages {
            shells: vec![
                vec![[0.5, 0.0, 0.0, 0.5]],
                vec![[0.0, 0.25, 0.0, 0.25]],
                vec![[9.0, 9.0, 9.0, 1.0]],
            ],
            ..TermImages::default()
        };
        assert_eq!(
            through(&term, 0, 0),
            Some(([0.0; 3], 1.0)),
            "no nearer layer"
        );
        assert_eq!(through(&term, 0, 1), Some(([0.5, 0.0, 0.0], 0.5)));
        // The second layer shows through the first's uncovered half.
        assert_eq!(through(&term, 0, 2), Some(([0.5, 0.125, 0.0], 0.375)));
        assert_eq!(through(&term, 1, 1), None, "no such pixel");
        assert_eq!(through(&term, 0, 4), None, "no such layers");
    }
}
