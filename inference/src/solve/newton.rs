//! Range term by damped Newton around PCG: the objective (halved)
//! F(x) = ½xᵀMx − rhsᵀx + ½λ_b s² Σ g(x_i/s) is strictly convex on the box
//! (−δ s, (1+δ) s), so Newton steps (M + diag(½λ_b g″)) Δ = −∇F solved
//! inexactly by PCG, with a backtracking line search that stays inside the
//! box and decreases F, converge to the unique minimizer.

use super::cg::{CgOutcome, pcg};
use super::operator::Operator;
use super::range::{RANGE_DELTA, g, g_derivatives};
use super::vecops::{dot, for_each_mut, norm};

const MAX_NEWTON: u32 = 40;
/// Inexact-Newton forcing term: each step's CG stops at 10% of ‖∇F‖.
const FORCING: f64 = 0.1;

fn barrier(x: &[f64], s: f64) -> f64 {
    x.iter().map(|&v| g(v / s)).sum()
}

/// Weights and budget of the range-term refinement.
#[derive(Clone, Copy)]
pub(crate) struct RangeTerm {
    /// ε_b (n_s/n_t) / (g(0) − g(½)).
    pub lambda_b: f64,
    /// Texel range [0, s].
    pub s: f64,
    pub tolerance: f64,
    pub max_iterations: u32,
}

/// Continues from `x` (clamped into [0, s]); `iterations_used` CG
/// iterations were spent before and count against `max_iterations`.
pub(crate) fn refine(
    op: &Operator,
    rhs: &[f64],
    x: &mut [f64],
    term: &RangeTerm,
    iterations_used: u32,
) -> CgOutcome {
    let RangeTerm {
        lambda_b,
        s,
        tolerance,
        max_iterations,
    } = *term;
    let n = x.len();
    let rhs_norm = norm(rhs);
    // The barrier acts on x/s; weighting it by s² too makes the whole
    // objective scale by s² when b and the range do, so an HDR layer solved
    // with s = max(b) gives exactly the LDR answer times s.
    let w = 0.5 * lambda_b * s * s;
    for_each_mut(x, |_, v| *v = v.clamp(0.0, s));
    let mut iterations = iterations_used;
    let mut scratch = op.scratch();
    let (mut mx, mut grad, mut d) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut step, mut mstep, mut trial) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut rel = f64::INFINITY;
    for _ in 0..MAX_NEWTON {
        op.apply(x, &mut mx, &mut scratch, None);
        for_each_mut(&mut grad, |i, v| {
            *v = mx[i] - rhs[i] + w / s * g_derivatives(x[i] / s).0;
        });
        rel = norm(&grad) / rhs_norm;
        let out = |iterations, converged, diagnostic| CgOutcome {
            iterations,
            relative_residual: rel,
            converged,
            diagnostic,
        };
        if !rel.is_finite() {
            return out(
                iterations,
                false,
                Some("range term: gradient became non-finite".into()),
            );
        }
        if rel <= tolerance {
            return out(iterations, true, None);
        }
        if iterations >= max_iterations {
            return out(
                iterations,
                false,
                Some(format!(
                    "range term: max_iterations = {max_iterations} reached at gradient {rel:.3e}"
                )),
            );
        }
        for_each_mut(&mut d, |i, v| *v = w / (s * s) * g_derivatives(x[i] / s).1);
        for_each_mut(&mut trial, |i, v| *v = -grad[i]);
        step.iter_mut().for_each(|v| *v = 0.0);
        let inner = pcg(
            op,
            Some(&d),
            &trial,
            &mut step,
            FORCING,
            max_iterations - iterations,
        );
        iterations += inner.iterations;
        let slope = dot(&grad, &step);
        if slope.is_nan() || slope >= 0.0 {
            return out(
                iterations,
                false,
                Some(format!(
                    "range term: Newton step is not a descent direction ({slope:.3e})"
                )),
            );
        }
        op.apply(&step, &mut mstep, &mut scratch, None);
        let curvature = dot(&step, &mstep);
        let quad_slope = slope - w / s * dot_barrier_grad(x, &step, s);
        // Largest step keeping every texel strictly inside (−δ s, (1+δ) s).
        let mut alpha: f64 = 1.0;
        for (xi, di) in x.iter().zip(&step) {
            let room = if *di > 0.0 {
                ((1.0 + RANGE_DELTA) * s - xi) / di
            } else if *di < 0.0 {
                (-RANGE_DELTA * s - xi) / di
            } else {
                f64::INFINITY
            };
            alpha = alpha.min(0.99 * room);
        }
        let b0 = barrier(x, s);
        let mut accepted = false;
        for _ in 0..60 {
            for_each_mut(&mut trial, |i, v| *v = x[i] + alpha * step[i]);
            let change = alpha * quad_slope
                + 0.5 * alpha * alpha * curvature
                + w * (barrier(&trial, s) - b0);
            if change.is_finite() && change <= 1e-4 * alpha * slope {
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            return out(
                iterations,
                false,
                Some(format!(
                    "range term: line search failed at gradient {rel:.3e}"
                )),
            );
        }
        x.copy_from_slice(&trial);
    }
    CgOutcome {
        iterations,
        relative_residual: rel,
        converged: false,
        diagnostic: Some(format!(
            "range term: {MAX_NEWTON} Newton steps without reaching the tolerance"
        )),
    }
}

/// Σ g′(x_i/s) Δ_i: the barrier's share of ∇F·Δ (divided by w/s).
fn dot_barrier_grad(x: &[f64], step: &[f64], s: f64) -> f64 {
    x.iter()
        .zip(step)
        .map(|(&v, &d)| g_derivatives(v / s).0 * d)
        .sum()
}
