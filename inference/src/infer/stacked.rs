//! View-independent textures (thesis §3, "multi-view"): the rendering
//! matrices and targets of several views are stacked into one system and
//! solved once, so every texel seen by any view is fitted to all of them.
//! With many rows the solver picks the AᵀA form by the K rule.

use super::layer::{InferError, Target, psnr_over_rows, texels};
use crate::probe::{ProbeGeometry, ProbeRenderer, build_matrix};
use crate::solve::csr::CsrMatrix;
use crate::solve::layout::{TextureLayout, TextureShape};
use crate::solve::{SolveOptions, solve_channels};
use std::time::{Duration, Instant};

pub struct StackedResult {
    pub layout: TextureLayout,
    pub map: Vec<Vec<f32>>,
    /// Least-squares PSNR of the one map rendered in each view.
    pub psnr_per_view_db: Vec<f64>,
    pub rows: usize,
    pub probe_renders: u32,
    pub iterations: Vec<u32>,
    pub solve_time: Duration,
}

pub fn infer_stacked(
    renderer: &mut dyn ProbeRenderer,
    views: &[(ProbeGeometry, Target)],
    shape: TextureShape,
    options: &SolveOptions,
) -> Result<StackedResult, InferError> {
    let layout = TextureLayout::full_chain(shape);
    let channels = views.first().map_or(3, |(_, t)| t.channels);
    let mut matrices = Vec::with_capacity(views.len());
    let mut bs: Vec<Vec<f32>> = vec![Vec::new(); channels];
    let mut probe_renders = 0;
    for (geometry, target) in views {
        if let Some((pixel, channel)) = target.pixels.iter().enumerate().find_map(|(p, v)| {
            v.iter()
                .take(channels)
                .position(|c| !c.is_finite())
                .map(|c| (p, c))
        }) {
            return Err(InferError::NonFinite {
                layer: target.name.into(),
                pixel,
                channel,
            });
        }
        let m = build_matrix(renderer, geometry, &layout, shape, &mut |_, _| {})?;
        probe_renders += m.probe_renders;
        for (c, b) in bs.iter_mut().enumerate() {
            b.extend(m.pixels.iter().map(|&p| target.pixels[p as usize][c]));
        }
        matrices.push(m);
    }
    let parts: Vec<&CsrMatrix> = matrices.iter().map(|m| &m.a).collect();
    let a = CsrMatrix::vstack(&parts)?;
    let b_refs: Vec<&[f32]> = bs.iter().map(Vec::as_slice).collect();
    let start = Instant::now();
    let solutions = solve_channels(&a, &b_refs, &layout, None, options)?;
    let solve_time = start.elapsed();
    let map: Vec<Vec<f32>> = solutions.iter().map(|s| s.x.clone()).collect();
    let content = texels(&map, layout.len());
    let mut psnr_per_view_db = Vec::with_capacity(views.len());
    for ((geometry, target), m) in views.iter().zip(&matrices) {
        let image = renderer.render(geometry, &layout, &content)?;
        psnr_per_view_db.push(psnr_over_rows(&image, target, &m.pixels));
    }
    Ok(StackedResult {
        rows: a.rows,
        layout,
        map,
        psnr_per_view_db,
        probe_renders,
        iterations: solutions.iter().map(|s| s.iterations).collect(),
        solve_time,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::infer::shift_device::{ShiftDevice as Device, shifted_view as view};

    #[test]
    fn two_half_views_recover_the_whole_texture() {
        let truth = |x: u32, y: u32| [0.1 + 0.05 * x as f32, 0.2 + 0.1 * y as f32, 0.5, 1.0];
        let pixels = |offset: u32| -> Vec<[f32; 4]> {
            (0..32).map(|p| truth(p % 8 + offset, p / 8)).collect()
        };
        let (left, right) = (pixels(0), pixels(8));
        let views = vec![
            (
                view(0),
                Target {
                    name: "left",
                    pixels: &left,
                    channels: 3,
                },
            ),
            (
                view(8),
                Target {
                    name: "right",
                    pixels: &right,
                    channels: 3,
                },
            ),
        ];
        let shape = TextureShape::Tex2D {
            width: 16,
            height: 4,
        };
        let exact = SolveOptions {
            eps_f: 0.0,
            ..SolveOptions::default()
        };
        let r = infer_stacked(&mut Device, &views, shape, &exact).expect("stacked");
        assert_eq!(r.rows, 64);
        for y in 0..4 {
            for x in 0..16 {
                let i = r.layout.index(0, 0, x, y);
                let t = truth(x, y);
                assert!(
                    (r.map[0][i] - t[0]).abs() < 1e-3 && (r.map[1][i] - t[1]).abs() < 1e-3,
                    "texel ({x}, {y})"
                );
            }
        }
        assert!(
            r.psnr_per_view_db.iter().all(|&p| p > 60.0),
            "{:?}",
            r.psnr_per_view_db
        );
    }
}
