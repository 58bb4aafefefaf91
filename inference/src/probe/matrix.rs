//! The rendering matrix A by probe renders, and its check against the
//! device: for random content x, `A x` must equal an actual render of x.
//!
//! Texel identification, float form: in a probe render the probed texels
//! carry (1, k, k², 0), every other texel 0, where k is the texel's 1-based
//! place in its set. A pixel then reads R = w (the filter weight of the one
//! probed texel it reaches), G = w·k and B = w·k², so k = G/R exactly up to
//! fp32 rounding; B/R = (G/R)² holds only when a single probed texel
//! contributes, which detects any collision. The thesis's variant keeps
//! the ID constant over each probed texel's filter neighbourhood because
//! its channels were 8-bit; on float textures (exact on lavapipe, see
//! README "Device notes") the product form needs no neighbourhood rules.

use super::schedule::ProbeSchedule;
use super::{ProbeError, ProbeGeometry, ProbeRenderer};
use crate::solve::correct_row_sums;
use crate::solve::csr::{CsrBuilder, CsrMatrix};
use crate::solve::layout::{TextureLayout, TextureShape};

/// Weights below this are truncated (the row-sum correction restores them).
const MIN_WEIGHT: f32 = 1e-6;
/// A pixel whose check channel disagrees by more than this saw two texels;
/// below it the second texel's weight is too small to matter.
const COLLISION_TOLERANCE: f32 = 1e-3;

pub struct RenderingMatrix {
    /// Rows = visible pixels (`pixels[row]` = y·width + x), columns = texels.
    pub a: CsrMatrix,
    pub pixels: Vec<u32>,
    /// Renders made: one coverage render plus one per probe set.
    pub probe_renders: u32,
    /// Rows whose weights summed below 1 and were corrected.
    pub corrected_rows: usize,
    /// Rows with weights on more than one cube face: the device filters
    /// across face edges (seamless cube maps) where this is non-zero.
    pub rows_across_faces: usize,
}

/// Builds A for `geometry` over a texture of `layout` with the engine's
/// probe schedule, calling `progress` with (done, total) after each render.
pub fn build_matrix(
    renderer: &mut dyn ProbeRenderer,
    geometry: &ProbeGeometry,
    layout: &TextureLayout,
    shape: TextureShape,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RenderingMatrix, ProbeError> {
    let schedule = ProbeSchedule::new(layout, shape);
    build_matrix_with(renderer, geometry, layout, &schedule, progress)
}

/// As [`build_matrix`] with a given schedule (every texel of `layout` in
/// exactly one set; the thesis's, to compare).
pub fn build_matrix_with(
    renderer: &mut dyn ProbeRenderer,
    geometry: &ProbeGeometry,
    layout: &TextureLayout,
    schedule: &ProbeSchedule,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<RenderingMatrix, ProbeError> {
    let total = schedule.sets.len() + 1;
    let pixel_count = geometry.width as usize * geometry.height as usize;

    // Coverage: visible pixels become rows.
    let ones = vec![[1.0, 0.0, 0.0, 0.0]; layout.len()];
    let coverage = render_checked(renderer, geometry, layout, &ones, pixel_count)?;
    let pixels: Vec<u32> = (0..pixel_count as u32)
        .filter(|&p| coverage[p as usize][3] > 0.5)
        .collect();
    progress(1, total);

    let mut rows: Vec<Vec<(u32, f32)>> = vec![Vec::new(); pixels.len()];
    let mut texels = vec![[0.0f32; 4]; layout.len()];
    for (set_index, set) in schedule.sets.iter().enumerate() {
        for (k, &t) in set.texels.iter().enumerate() {
            let id = (k + 1) as f32;
            texels[t] = [1.0, id, id * id, 0.0];
        }
        let image = render_checked(renderer, geometry, layout, &texels, pixel_count)?;
        let mut collisions = 0;
        for (row, &p) in pixels.iter().enumerate() {
            let [w, wk, wk2, _] = image[p as usize];
            if w.is_nan() || w <= MIN_WEIGHT {
                continue;
            }
            let k = wk / w;
            let id = k.round();
            let expected_square = id * id;
            let consistent = (k - id).abs() < 0.01
                && ((wk2 / w) - expected_square).abs()
                    <= COLLISION_TOLERANCE * expected_square.max(1.0);
            match set.texels.get((id as usize).wrapping_sub(1)) {
                Some(&texel) if consistent => rows[row].push((texel as u32, w)),
                _ if w > COLLISION_TOLERANCE => collisions += 1,
                _ => {} // a negligible second weight: truncated like any other
            }
        }
        if collisions > 0 {
            return Err(ProbeError::Collision {
                set: set_index,
                pixels: collisions,
            });
        }
        for &t in &set.texels {
            texels[t] = [0.0; 4];
        }
        progress(set_index + 2, total);
    }

    let mut builder = CsrBuilder::new(layout.len());
    for row in &rows {
        builder.push_row(row)?;
    }
    let mut a = builder.finish();
    let corrected_rows = correct_row_sums(&mut a, 1.0);
    let rows_across_faces = rows
        .iter()
        .filter(|r| {
            let mut faces = r.iter().map(|&(t, _)| layout.coords(t as usize).0);
            faces.next().is_some_and(|f| faces.any(|g| g != f))
        })
        .count();
    Ok(RenderingMatrix {
        a,
        pixels,
        probe_renders: total as u32,
        corrected_rows,
        rows_across_faces,
    })
}

fn render_checked(
    renderer: &mut dyn ProbeRenderer,
    geometry: &ProbeGeometry,
    layout: &TextureLayout,
    texels: &[[f32; 4]],
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>, ProbeError> {
    let image = renderer.render(geometry, layout, texels)?;
    if image.len() != pixel_count {
        return Err(ProbeError::Mismatch {
            what: "probe render size",
            expected: format!("{pixel_count} pixels"),
            got: format!("{} pixels", image.len()),
        });
    }
    Ok(image)
}

/// How well `A x` predicts a real render of random content x.
#[derive(Clone, Copy, Debug)]
pub struct VerifyReport {
    /// Worst of the RGB channels; peak = the render's maximum.
    pub psnr_db: f64,
    pub max_abs_error: f32,
}

/// Renders deterministic pseudo-random content (seeded) and compares every
/// visible pixel and channel with `A x`.
pub fn verify_matrix(
    renderer: &mut dyn ProbeRenderer,
    geometry: &ProbeGeometry,
    layout: &TextureLayout,
    matrix: &RenderingMatrix,
    seed: u64,
) -> Result<VerifyReport, ProbeError> {
    let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        // splitmix64: reproducible content, no dependency.
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let texels: Vec<[f32; 4]> = (0..layout.len())
        .map(|_| [next(), next(), next(), 1.0])
        .collect();
    let pixel_count = geometry.width as usize * geometry.height as usize;
    let image = render_checked(renderer, geometry, layout, &texels, pixel_count)?;
    let mut worst_psnr = f64::INFINITY;
    let mut max_abs_error = 0.0f32;
    let mut predicted = vec![0.0f32; matrix.a.rows];
    for c in 0..3 {
        let x: Vec<f32> = texels.iter().map(|t| t[c]).collect();
        matrix.a.mul(&x, &mut predicted);
        let mut peak = 0.0f32;
        let mut sum_sq = 0.0f64;
        for (row, &p) in matrix.pixels.iter().enumerate() {
            let actual = image[p as usize][c];
            let error = actual - predicted[row];
            peak = peak.max(actual.abs());
            max_abs_error = max_abs_error.max(error.abs());
            sum_sq += f64::from(error) * f64::from(error);
        }
        let mse = sum_sq / matrix.pixels.len().max(1) as f64;
        let psnr = if mse == 0.0 {
            f64::INFINITY
        } else {
            10.0 * (f64::from(peak).powi(2) / mse).log10()
        };
        worst_psnr = worst_psnr.min(psnr);
    }
    Ok(VerifyReport {
        psnr_db: worst_psnr,
        max_abs_error,
    })
}
