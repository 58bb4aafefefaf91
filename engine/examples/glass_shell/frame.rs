//! The thesis's formulation of the shell solve (`--frame` of
//! `glass_shell_infer`): the traced frame itself, both terms at once. Row p,
//! channel c: `w_T,c(p)·A_T[p] + w_R,c(p)·A_R[p]` against the traced
//! frame's pixel, over the pixels the lens covers wholly; `A_T`, `A_R` the
//! probe-rendered matrices of the two terms' lookups, `w` the traced mean
//! `F·G` of each term at the pixel.

use std::collections::HashMap;

use engine::probe::VulkanProbe;
use inference::glass::targets::GlassTargets;
use inference::probe::{ProbeGeometry, build_matrix};
use inference::solve::csr::CsrMatrix;
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::solve::{SolveOptions, solve_channels};

type Error = Box<dyn std::error::Error>;

/// One view: the two terms' probe geometry, the targets (weights,
/// coverage) and an independently traced frame (RGB per pixel).
pub struct FrameView {
    pub t: ProbeGeometry,
    pub r: ProbeGeometry,
    pub targets: GlassTargets,
    pub beauty: Vec<[f32; 3]>,
}

/// Row `row` of `a` scaled by `s`, appended to `entries`.
fn push_row(entries: &mut Vec<(u32, f32)>, a: &CsrMatrix, row: usize, s: f32) {
    let span = a.row_ptr[row]..a.row_ptr[row + 1];
    entries.extend(
        a.col_idx[span.clone()]
            .iter()
            .zip(&a.values[span])
            .map(|(&c, &v)| (c, s * v)),
    );
}

/// Sorted, merged entries of one row appended to `m`.
fn close_row(m: &mut CsrMatrix, entries: &mut Vec<(u32, f32)>) {
    entries.sort_unstable_by_key(|e| e.0);
    let mut last: Option<u32> = None;
    for &(c, v) in entries.iter() {
        if last == Some(c) {
            if let Some(x) = m.values.last_mut() {
                *x += v;
            }
        } else {
            m.col_idx.push(c);
            m.values.push(v);
            last = Some(c);
        }
    }
    entries.clear();
    m.rows += 1;
    m.row_ptr.push(m.values.len());
}

/// Per channel, the combined rows of every view and their targets.
fn system(
    probe: &mut VulkanProbe,
    views: &[FrameView],
    layout: &TextureLayout,
    shape: TextureShape,
) -> Result<(Vec<CsrMatrix>, Vec<Vec<f32>>), Error> {
    let mut a: Vec<CsrMatrix> = (0..3).map(|_| CsrMatrix::zeros(0, layout.len())).collect();
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
            if cov < 1.0 {
                continue;
            }
            let (wt, wr) = (v.targets.t.weight[pu], v.targets.r.weight[pu]);
            for c in 0..3 {
                push_row(&mut entries, &at.a, i, wt[c]);
                push_row(&mut entries, &ar.a, j, wr[c]);
                close_row(&mut a[c], &mut entries);
                b[c].push(v.beauty[pu][c]);
            }
        }
    }
    Ok((a, b))
}

/// `b − A x`.
fn residual(a: &CsrMatrix, x: &[f32], b: &[f32]) -> Vec<f32> {
    (0..a.rows)
        .map(|r| {
            let span = a.row_ptr[r]..a.row_ptr[r + 1];
            let ax: f32 = a.col_idx[span.clone()]
                .iter()
                .zip(&a.values[span])
                .map(|(&c, &v)| v * x[c as usize])
                .sum();
            b[r] - ax
        })
        .collect()
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
) -> Result<Vec<Vec<f32>>, Error> {
    let layout = TextureLayout::full_chain(shape);
    let (a, b) = system(probe, views, &layout, shape)?;
    let options = SolveOptions {
        eps_prior: refine.unwrap_or(0.0),
        ..SolveOptions::default()
    };
    let mut map = Vec::new();
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
        let x = s.into_iter().next().ok_or("no solution")?;
        eprintln!(
            "channel {c}: {} rows, {} CG iterations, relative residual {:.2e}",
            a[c].rows, x.iterations, x.relative_residual
        );
        map.push(match refine {
            Some(_) => traced[c].iter().zip(&x.x).map(|(t, d)| t + d).collect(),
            None => x.x,
        });
    }
    Ok(map)
}
