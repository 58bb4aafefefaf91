//! A view-independent texture that the device multiplies with a known
//! per-pixel factor — a light map under an albedo texture: pixel =
//! `f_p ⊙ (A x)_p`. Still linear in the texels: each view's rendering
//! matrix A comes from probe renders of the texture alone (papers.md §1),
//! its rows are scaled per channel by the factor the device itself sampled
//! at that pixel, and the rows of every view are stacked into one solve per
//! channel (thesis: "multi-view", AᵀA form by the K rule).

use super::layer::{InferError, Target, psnr_over_rows, texels};
use crate::probe::{ProbeGeometry, ProbeRenderer, build_matrix};
use crate::solve::csr::CsrMatrix;
use crate::solve::layout::{TextureLayout, TextureShape};
use crate::solve::{SolveOptions, solve};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Channels of a factored texture (RGB).
const CHANNELS: usize = 3;

/// One view of the object.
pub struct FactoredView<'a> {
    /// For messages, e.g. `floor.diffuse at az +0 el +30`.
    pub name: &'a str,
    pub geometry: ProbeGeometry,
    /// The radiance to reproduce, full frame, RGB (A ignored).
    pub target: &'a [[f32; 4]],
    /// The known factor at every pixel, RGB: what the device samples there.
    pub factor: &'a [[f32; 4]],
    /// Pixels that may be rows (where the target shows this object).
    pub usable: &'a [bool],
}

pub struct FactoredResult {
    pub layout: TextureLayout,
    /// One Vec per channel (R, G, B), layout order.
    pub map: Vec<Vec<f32>>,
    /// Per view: PSNR of `factor ⊙ render(map)` against the target over its
    /// rows (peak = the target's maximum there).
    pub psnr_per_view_db: Vec<f64>,
    /// Per view: the rows' pixels and the device's render of the map.
    pub rows_per_view: Vec<Vec<u32>>,
    pub renders: Vec<Vec<[f32; 4]>>,
    pub rows: usize,
    pub probe_renders: u32,
    pub iterations: Vec<u32>,
    pub probe_time: Duration,
    pub solve_time: Duration,
}

/// The rows of one view: pixels and, per channel, the scaled CSR parts.
struct ViewRows {
    pixels: Vec<u32>,
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    weights: Vec<f32>,
}

fn check_view(view: &FactoredView) -> Result<(), InferError> {
    let expected = view.geometry.width as usize * view.geometry.height as usize;
    for (what, got) in [
        ("target", view.target.len()),
        ("factor", view.factor.len()),
        ("usable", view.usable.len()),
    ] {
        if got != expected {
            return Err(InferError::Size {
                layer: format!("{} ({what})", view.name),
                got,
                expected,
            });
        }
    }
    for (p, _) in view.usable.iter().enumerate().filter(|(_, u)| **u) {
        for (image, what) in [(view.target, "target"), (view.factor, "factor")] {
            if let Some(channel) = image[p][..CHANNELS].iter().position(|v| !v.is_finite()) {
                return Err(InferError::NonFinite {
                    layer: format!("{} ({what})", view.name),
                    pixel: p,
                    channel,
                });
            }
        }
    }
    Ok(())
}

/// The rows of `view`'s rendering matrix whose pixels are usable.
fn view_rows(
    renderer: &mut dyn ProbeRenderer,
    view: &FactoredView,
    layout: &TextureLayout,
    shape: TextureShape,
) -> Result<(ViewRows, u32), InferError> {
    let m = build_matrix(renderer, &view.geometry, layout, shape, &mut |_, _| {})?;
    let mut rows = ViewRows {
        pixels: Vec::new(),
        row_ptr: vec![0],
        cols: Vec::new(),
        weights: Vec::new(),
    };
    for (r, &p) in m.pixels.iter().enumerate() {
        if !view.usable[p as usize] {
            continue;
        }
        let span = m.a.row_ptr[r]..m.a.row_ptr[r + 1];
        rows.pixels.push(p);
        rows.cols.extend_from_slice(&m.a.col_idx[span.clone()]);
        rows.weights.extend_from_slice(&m.a.values[span]);
        rows.row_ptr.push(rows.cols.len());
    }
    Ok((rows, m.probe_renders))
}

/// Channel `c` of all views' rows stacked: weights × the factor, and b.
fn channel_system(
    views: &[FactoredView],
    rows: &[ViewRows],
    cols: usize,
    c: usize,
) -> (CsrMatrix, Vec<f32>) {
    let mut a = CsrMatrix::zeros(0, cols);
    let mut b = Vec::new();
    for (view, r) in views.iter().zip(rows) {
        let base = a.col_idx.len();
        for (i, &p) in r.pixels.iter().enumerate() {
            let f = view.factor[p as usize][c];
            let span = r.row_ptr[i]..r.row_ptr[i + 1];
            a.col_idx.extend_from_slice(&r.cols[span.clone()]);
            a.values.extend(r.weights[span].iter().map(|w| w * f));
            a.row_ptr.push(base + r.row_ptr[i + 1]);
            b.push(view.target[p as usize][c]);
        }
    }
    a.rows = b.len();
    (a, b)
}

/// One texture for every view in `views`, each pixel the device's factor
/// times the texture's sample, fitted to the targets by the regularized
/// least squares of [`crate::solve`].
pub fn infer_factored(
    renderer: &mut dyn ProbeRenderer,
    views: &[FactoredView],
    shape: TextureShape,
    options: &SolveOptions,
) -> Result<FactoredResult, InferError> {
    views.iter().try_for_each(check_view)?;
    let layout = TextureLayout::full_chain(shape);
    let start = Instant::now();
    let mut rows = Vec::with_capacity(views.len());
    let mut probe_renders = 0;
    for view in views {
        let (r, n) = view_rows(renderer, view, &layout, shape)?;
        probe_renders += n;
        rows.push(r);
    }
    let probe_time = start.elapsed();
    let start = Instant::now();
    let solutions = (0..CHANNELS)
        .into_par_iter()
        .map(|c| {
            let (a, b) = channel_system(views, &rows, layout.len(), c);
            solve(&a, &b, &layout, None, options)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let solve_time = start.elapsed();
    let map: Vec<Vec<f32>> = solutions.iter().map(|s| s.x.clone()).collect();
    let content = texels(&map, layout.len());
    let mut psnr_per_view_db = Vec::with_capacity(views.len());
    let mut renders = Vec::with_capacity(views.len());
    for (view, r) in views.iter().zip(&rows) {
        let image = renderer.render(&view.geometry, &layout, &content)?;
        let shaded: Vec<[f32; 4]> = image
            .iter()
            .zip(view.factor)
            .map(|(x, f)| [x[0] * f[0], x[1] * f[1], x[2] * f[2], x[3]])
            .collect();
        let target = Target {
            name: view.name,
            pixels: view.target,
            channels: CHANNELS,
        };
        psnr_per_view_db.push(psnr_over_rows(&shaded, &target, &r.pixels));
        renders.push(image);
    }
    Ok(FactoredResult {
        rows: rows.iter().map(|r| r.pixels.len()).sum(),
        rows_per_view: rows.into_iter().map(|r| r.pixels).collect(),
        layout,
        map,
        psnr_per_view_db,
        renders,
        probe_renders,
        iterations: solutions.iter().map(|s| s.iterations).collect(),
        probe_time,
        solve_time,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::infer::shift_device::{ShiftDevice as Device, shifted_view as geometry};

    #[test]
    fn a_light_map_under_a_known_albedo_is_recovered_from_two_views() {
        let light = |x: u32, y: u32| [1.0 + 0.25 * x as f32, 2.0 - 0.2 * y as f32, 0.5];
        // A checker albedo, different per channel, dark squares included.
        let albedo = |x: u32, y: u32| {
            let dark = (x + y) % 2 == 1;
            if dark {
                [0.1, 0.05, 0.2, 1.0]
            } else {
                [0.8, 0.7, 0.9, 1.0]
            }
        };
        let make = |offset: u32| -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
            (0..32)
                .map(|p| {
                    let (x, y) = (p % 8 + offset, p / 8);
                    let (l, a) = (light(x, y), albedo(x, y));
                    ([l[0] * a[0], l[1] * a[1], l[2] * a[2], 1.0], a)
                })
                .unzip()
        };
        let (left, left_albedo) = make(0);
        let (mut right, right_albedo) = make(8);
        // One pixel of the right view shows an occluder: not usable.
        right[5] = [100.0, 100.0, 100.0, 1.0];
        let mut usable_right = vec![true; 32];
        usable_right[5] = false;
        let all = vec![true; 32];
        let views = [
            FactoredView {
                name: "left",
                geometry: geometry(0),
                target: &left,
                factor: &left_albedo,
                usable: &all,
            },
            FactoredView {
                name: "right",
                geometry: geometry(8),
                target: &right,
                factor: &right_albedo,
                usable: &usable_right,
            },
        ];
        let shape = TextureShape::Tex2D {
            width: 16,
            height: 4,
        };
        let exact = SolveOptions {
            eps_f: 0.0,
            tolerance: 1e-7,
            ..SolveOptions::default()
        };
        let r = infer_factored(&mut Device, &views, shape, &exact).expect("solve");
        assert_eq!(r.rows, 63);
        for y in 0..4 {
            for x in 0..16 {
                if (x, y) == (13, 0) {
                    continue; // behind the occluder: seen by no row
                }
                let i = r.layout.index(0, 0, x, y);
                let want = light(x, y);
                for (c, want) in want.iter().enumerate() {
                    assert!(
                        (r.map[c][i] - want).abs() < 1e-3,
                        "texel ({x}, {y}) channel {c}"
                    );
                }
            }
        }
        assert!(
            r.psnr_per_view_db.iter().all(|&p| p > 60.0),
            "{:?}",
            r.psnr_per_view_db
        );
    }

    #[test]
    fn mismatched_or_non_finite_inputs_name_the_view() {
        let target = vec![[1.0; 4]; 32];
        let mut factor = vec![[1.0; 4]; 32];
        factor[3][1] = f32::NAN;
        let usable = vec![true; 32];
        let view = FactoredView {
            name: "floor",
            geometry: geometry(0),
            target: &target,
            factor: &factor,
            usable: &usable,
        };
        let shape = TextureShape::Tex2D {
            width: 16,
            height: 4,
        };
        let e = infer_factored(&mut Device, &[view], shape, &SolveOptions::default())
            .err()
            .map(|e| e.to_string());
        assert!(
            e.as_ref()
                .is_some_and(|e| e.contains("floor (factor)") && e.contains("pixel 3")),
            "{e:?}"
        );
        let short = vec![true; 31];
        let view = FactoredView {
            name: "floor",
            geometry: geometry(0),
            target: &target,
            factor: &target,
            usable: &short,
        };
        assert!(infer_factored(&mut Device, &[view], shape, &SolveOptions::default()).is_err());
    }
}
