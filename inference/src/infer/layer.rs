//! Infers one map (a cube EM layer or a 2D texture) for one view: probe
//! renders build A, the regularized solve fits the target, and the engine's
//! actual render of the result is compared with the target beside the
//! forward-mapping baseline.

use super::forward::forward_map;
use super::views::{MatrixCache, View, Views};
use crate::probe::{
    ProbeError, ProbeGeometry, ProbeRenderer, RenderingMatrix, build_matrix, verify_matrix,
};
use crate::solve::csr::CsrMatrix;
use crate::solve::layout::{TextureLayout, TextureShape};
use crate::solve::{Solution, SolveOptions, solve_channels};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What the map must reproduce: `channels` (3 or 4) of `pixels`.
#[derive(Clone, Copy)]
pub struct Target<'a> {
    pub name: &'a str,
    pub pixels: &'a [[f32; 4]],
    pub channels: usize,
}

pub struct LayerResult {
    pub name: String,
    pub layout: TextureLayout,
    /// Least-squares map, one Vec per channel, layout order.
    pub map: Vec<Vec<f32>>,
    pub forward: Vec<Vec<f32>>,
    pub probe_renders: u32,
    pub a_vs_render_psnr_db: f64,
    pub psnr_least_squares_db: f64,
    pub psnr_forward_db: f64,
    pub rows: usize,
    pub nnz: usize,
    /// Rows filtered across cube-face edges (see `RenderingMatrix`).
    pub rows_across_faces: usize,
    pub iterations: Vec<u32>,
    pub diagnostics: Vec<String>,
    pub probe_time: Duration,
    pub assembly_time: Duration,
    pub solve_time: Duration,
    /// The device's renders of the least-squares and forward-mapped maps
    /// (full frame, RGBA), and the object's pixels, for pictures.
    pub rendered_least_squares: Vec<[f32; 4]>,
    pub rendered_forward: Vec<[f32; 4]>,
    pub pixels: Vec<u32>,
}

/// Times the renderer so probe renders and matrix assembly can be told apart.
struct Timed<'a> {
    inner: &'a mut dyn ProbeRenderer,
    spent: Duration,
}

impl ProbeRenderer for Timed<'_> {
    fn render(
        &mut self,
        g: &ProbeGeometry,
        l: &TextureLayout,
        t: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError> {
        let start = Instant::now();
        let image = self.inner.render(g, l, t);
        self.spent += start.elapsed();
        image
    }
}

#[derive(Debug, thiserror::Error)]
pub enum InferError {
    #[error(transparent)]
    Probe(#[from] ProbeError),
    #[error(transparent)]
    Solve(#[from] crate::solve::SolveError),
    #[error(
        "layer {layer}: non-finite value at pixel {pixel} channel {channel} (expected finite floats)"
    )]
    NonFinite {
        layer: String,
        pixel: usize,
        channel: usize,
    },
    #[error("layer {layer}: {got} pixels, the view has {expected}")]
    Size {
        layer: String,
        got: usize,
        expected: usize,
    },
    #[error(
        "layer {layer}: pixel weights: {got} values, the view has {expected} pixels (expected one finite weight ≥ 0 per pixel)"
    )]
    WeightCount {
        layer: String,
        got: usize,
        expected: usize,
    },
    #[error("layer {layer}: pixel weight {value} at pixel {pixel} (expected finite and ≥ 0)")]
    BadWeight {
        layer: String,
        pixel: usize,
        value: f32,
    },
}

/// Interleaves per-channel maps into RGBA texels (alpha 1 when absent).
pub fn texels(map: &[Vec<f32>], len: usize) -> Vec<[f32; 4]> {
    (0..len)
        .map(|i| std::array::from_fn(|c| map.get(c).map_or(1.0, |m| m[i])))
        .collect()
}

/// The device's render of `map`. The renderer writes coverage into the
/// alpha channel, not the map's alpha, so a 4-channel map's alpha is
/// rendered on its own (as grey, `[a, a, a, 1]`) and put in place: the
/// scores then see the alpha the layer will composite with.
fn render_with_alpha(
    renderer: &mut dyn ProbeRenderer,
    geometry: &ProbeGeometry,
    layout: &TextureLayout,
    map: &[Vec<f32>],
) -> Result<Vec<[f32; 4]>, ProbeError> {
    let n = layout.len();
    let mut image = renderer.render(geometry, layout, &texels(map, n))?;
    if let Some(alpha) = map.get(3) {
        let grey: Vec<[f32; 4]> = alpha.iter().map(|&a| [a, a, a, 1.0]).collect();
        let rendered = renderer.render(geometry, layout, &grey)?;
        for (pixel, a) in image.iter_mut().zip(&rendered) {
            pixel[3] = a[0];
        }
    }
    Ok(image)
}

/// PSNR over the rows' pixels and the target's channels; peak = the
/// target's largest value there (HDR-safe), ∞ when identical.
pub fn psnr_over_rows(image: &[[f32; 4]], target: &Target, pixels: &[u32]) -> f64 {
    let mut peak = 0.0f64;
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for &p in pixels {
        let (want, got) = (&target.pixels[p as usize], &image[p as usize]);
        for (t, g) in want.iter().zip(got).take(target.channels) {
            let t = f64::from(*t);
            let d = f64::from(*g) - t;
            peak = peak.max(t.abs());
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 {
        return f64::NAN;
    }
    let mse = sum / n as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else if peak == 0.0 {
        f64::NEG_INFINITY
    } else {
        10.0 * (peak * peak / mse).log10()
    }
}

pub fn infer_layer(
    renderer: &mut dyn ProbeRenderer,
    geometry: &ProbeGeometry,
    shape: TextureShape,
    target: &Target,
    warm_start: Option<&[Vec<f32>]>,
    options: &SolveOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<LayerResult, InferError> {
    let own = View {
        id: 0,
        geometry,
        target: *target,
        weight: 1.0,
        pixel_weights: None,
    };
    let views = Views {
        own,
        neighbours: &[],
        cache: &mut MatrixCache::new(0),
    };
    infer_layer_with(renderer, views, shape, warm_start, options, progress)
}

/// [`infer_layer`] with neighbouring views' rows stacked into the solve,
/// each view's rows scaled by its weight, and matrices taken from (and
/// kept in) the views' cache.
pub fn infer_layer_with(
    renderer: &mut dyn ProbeRenderer,
    views: Views,
    shape: TextureShape,
    warm_start: Option<&[Vec<f32>]>,
    options: &SolveOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<LayerResult, InferError> {
    let Views {
        own,
        neighbours,
        cache,
    } = views;
    let (geometry, target) = (own.geometry, &own.target);
    let expected = check_target(geometry, target)?;
    check_weights(&own)?;
    let layout = TextureLayout::full_chain(shape);
    let mut timed = Timed {
        inner: renderer,
        spent: Duration::ZERO,
    };
    let start = Instant::now();
    let matrix = cache.get_or_build(own.id, layout.len(), || {
        build_matrix(&mut timed, geometry, &layout, shape, progress)
    })?;
    let mut extras = Vec::new();
    for n in neighbours {
        check_target(n.geometry, &n.target)?;
        check_weights(n)?;
        let m = cache.get_or_build(n.id, layout.len(), || {
            build_matrix(&mut timed, n.geometry, &layout, shape, &mut |_, _| {})
        })?;
        extras.push(Stacked {
            matrix: m,
            target: &n.target,
            weight: n.weight,
            pixel_weights: n.pixel_weights,
        });
    }
    let build_time = start.elapsed();
    let probe_time = timed.spent;
    let verify = verify_matrix(&mut timed, geometry, &layout, &matrix, 1)?;
    let own_rows = Stacked {
        matrix: Arc::clone(&matrix),
        target,
        weight: 1.0,
        pixel_weights: own.pixel_weights,
    };
    let (solutions, solve_time) = solve_target(own_rows, &extras, &layout, warm_start, options)?;
    let forward = forward_maps(&matrix, target, &layout, geometry.width, expected);
    let map: Vec<Vec<f32>> = solutions.iter().map(|s| s.x.clone()).collect();
    let rendered_ls = render_with_alpha(&mut timed, geometry, &layout, &map)?;
    let rendered_fm = render_with_alpha(&mut timed, geometry, &layout, &forward)?;
    let psnr_least_squares_db = psnr_over_rows(&rendered_ls, target, &matrix.pixels);
    let psnr_forward_db = psnr_over_rows(&rendered_fm, target, &matrix.pixels);
    Ok(LayerResult {
        name: target.name.into(),
        psnr_least_squares_db,
        psnr_forward_db,
        a_vs_render_psnr_db: verify.psnr_db,
        probe_renders: matrix.probe_renders,
        rows: matrix.pixels.len(),
        nnz: matrix.a.nnz(),
        rows_across_faces: matrix.rows_across_faces,
        iterations: solutions.iter().map(|s| s.iterations).collect(),
        diagnostics: solutions
            .iter()
            .filter_map(|s| s.diagnostic.clone())
            .collect(),
        probe_time,
        assembly_time: build_time.saturating_sub(probe_time),
        solve_time,
        layout,
        map,
        forward,
        rendered_least_squares: rendered_ls,
        rendered_forward: rendered_fm,
        pixels: matrix.pixels.clone(),
    })
}

/// Checks the target's size against the probe view and that it is all
/// finite; returns its pixel count.
fn check_target(geometry: &ProbeGeometry, target: &Target) -> Result<usize, InferError> {
    let expected = geometry.width as usize * geometry.height as usize;
    if target.pixels.len() != expected {
        return Err(InferError::Size {
            layer: target.name.into(),
            got: target.pixels.len(),
            expected,
        });
    }
    if let Some((pixel, channel)) = target
        .pixels
        .iter()
        .enumerate()
        .find_map(|(p, v)| v.iter().position(|c| !c.is_finite()).map(|c| (p, c)))
    {
        return Err(InferError::NonFinite {
            layer: target.name.into(),
            pixel,
            channel,
        });
    }
    Ok(expected)
}

/// A view's pixel weights, if it has them: one per pixel, finite, ≥ 0.
fn check_weights(view: &View) -> Result<(), InferError> {
    let Some(weights) = view.pixel_weights else {
        return Ok(());
    };
    let layer = || view.target.name.to_string();
    let expected = view.geometry.width as usize * view.geometry.height as usize;
    if weights.len() != expected {
        return Err(InferError::WeightCount {
            layer: layer(),
            got: weights.len(),
            expected,
        });
    }
    match weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
        Some(pixel) => Err(InferError::BadWeight {
            layer: layer(),
            pixel,
            value: weights[pixel],
        }),
        None => Ok(()),
    }
}

/// One view's rows in a solve: its rendering matrix and target, scaled by
/// `weight` and, per pixel, by `pixel_weights`.
struct Stacked<'m> {
    matrix: Arc<RenderingMatrix>,
    target: &'m Target<'m>,
    weight: f32,
    pixel_weights: Option<&'m [f32]>,
}

impl Stacked<'_> {
    /// The factor on row `i` (pixel `matrix.pixels[i]`).
    fn row_weight(&self, i: usize) -> f32 {
        // check_weights saw one weight per pixel of the view.
        let pixel = |w: &[f32]| {
            let p = self.matrix.pixels[i] as usize;
            w.get(p).copied().unwrap_or(1.0)
        };
        self.weight * self.pixel_weights.map_or(1.0, pixel)
    }

    fn weighted(&self) -> bool {
        self.weight != 1.0 || self.pixel_weights.is_some()
    }
}

/// The regularized least-squares solve of the stacked views' rows, each
/// row (and its target value) scaled by its view's factor.
fn solve_target(
    own: Stacked,
    extras: &[Stacked],
    layout: &TextureLayout,
    warm_start: Option<&[Vec<f32>]>,
    options: &SolveOptions,
) -> Result<(Vec<Solution>, Duration), InferError> {
    let views: Vec<&Stacked> = std::iter::once(&own).chain(extras).collect();
    let channels = own.target.channels;
    let bs: Vec<Vec<f32>> = (0..channels)
        .map(|c| {
            views
                .iter()
                .flat_map(|v| {
                    v.matrix
                        .pixels
                        .iter()
                        .enumerate()
                        .map(move |(i, &p)| v.row_weight(i) * v.target.pixels[p as usize][c])
                })
                .collect()
        })
        .collect();
    let b_refs: Vec<&[f32]> = bs.iter().map(Vec::as_slice).collect();
    let stacked;
    let a = if views.len() == 1 && !own.weighted() {
        &own.matrix.a
    } else {
        let parts: Vec<&CsrMatrix> = views.iter().map(|v| &v.matrix.a).collect();
        let mut s = CsrMatrix::vstack(&parts)?;
        // Each row scaled as its b was.
        let mut row = 0;
        for v in &views {
            if v.weighted() {
                for i in 0..v.matrix.a.rows {
                    let w = v.row_weight(i);
                    let values = s.row_ptr[row + i]..s.row_ptr[row + i + 1];
                    s.values[values].iter_mut().for_each(|x| *x *= w);
                }
            }
            row += v.matrix.a.rows;
        }
        stacked = s;
        &stacked
    };
    let warm: Option<Vec<&[f32]>> = warm_start
        .filter(|w| w.len() == channels && w.iter().all(|m| m.len() == layout.len()))
        .map(|w| w.iter().map(Vec::as_slice).collect());
    let start = Instant::now();
    let solutions = solve_channels(a, &b_refs, layout, warm.as_deref(), options)?;
    Ok((solutions, start.elapsed()))
}

/// The forward-mapped map per channel (the baseline the solve is measured
/// against).
fn forward_maps(
    matrix: &RenderingMatrix,
    target: &Target,
    layout: &TextureLayout,
    width: u32,
    expected: usize,
) -> Vec<Vec<f32>> {
    let object: Vec<bool> = {
        let mut mask = vec![false; expected];
        for &p in &matrix.pixels {
            mask[p as usize] = true;
        }
        mask
    };
    (0..target.channels)
        .map(|c| {
            let channel: Vec<f32> = target.pixels.iter().map(|v| v[c]).collect();
            forward_map(&matrix.a, &matrix.pixels, layout, width, &channel, &object)
        })
        .collect()
}
