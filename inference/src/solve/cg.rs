//! Jacobi-preconditioned conjugate gradient on the SPD (or PSD) operator.
//!
//! State is f64 so a 1e-4 … 1e-6 relative residual is reachable with f32
//! matrices. Convergence is judged on the true residual: when the recurrence
//! says "done", the residual is recomputed and CG restarts from there if
//! drift fooled it. Every loop is bounded by `max_iterations`.

use super::operator::Operator;
use super::vecops::{cg_update, dot, for_each_mut, norm};

pub(crate) struct CgOutcome {
    pub iterations: u32,
    /// ‖rhs − M x‖ / ‖rhs‖ (true residual, 0 when rhs = 0).
    pub relative_residual: f64,
    pub converged: bool,
    pub diagnostic: Option<String>,
}

/// Solves (M + diag(extra)) x = rhs in place, starting from `x`.
pub(crate) fn pcg(
    op: &Operator,
    extra: Option<&[f64]>,
    rhs: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: u32,
) -> CgOutcome {
    let n = rhs.len();
    let rhs_norm = norm(rhs);
    // Non-positive diagonal entries (columns nothing touches) get 1: those
    // residual components stay zero, so the value only has to be finite.
    let inv_diag: Vec<f64> = (0..n)
        .map(|i| {
            let d = op.diag[i] + extra.map_or(0.0, |e| e[i]);
            if d > 0.0 && d.is_finite() {
                1.0 / d
            } else {
                1.0
            }
        })
        .collect();
    let mut scratch = op.scratch();
    let (mut r, mut z, mut p, mut q) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut iterations = 0u32;
    let target = tolerance * rhs_norm;
    loop {
        // True residual r = rhs − M x.
        op.apply(x, &mut q, &mut scratch, extra);
        for_each_mut(&mut r, |i, v| *v = rhs[i] - q[i]);
        let r_norm = norm(&r);
        let rel = if rhs_norm > 0.0 {
            r_norm / rhs_norm
        } else {
            r_norm
        };
        let done = |converged, diagnostic| CgOutcome {
            iterations,
            relative_residual: rel,
            converged,
            diagnostic,
        };
        if !rel.is_finite() {
            return done(false, Some("residual became non-finite".into()));
        }
        if r_norm <= target || (rhs_norm == 0.0 && r_norm == 0.0) {
            return done(true, None);
        }
        if iterations >= max_iterations {
            return done(
                false,
                Some(format!(
                    "stopped at max_iterations = {max_iterations} with relative residual {rel:.3e} > tolerance {tolerance:.1e}"
                )),
            );
        }
        for_each_mut(&mut z, |i, v| *v = r[i] * inv_diag[i]);
        p.copy_from_slice(&z);
        let mut rz = dot(&r, &z);
        let mut breakdown = None;
        while iterations < max_iterations {
            op.apply(&p, &mut q, &mut scratch, extra);
            let pq = dot(&p, &q);
            // pᵀMp ≤ 0 means M is not positive definite along p (singular A
            // with ε_f = 0, or rounding): stop rather than divide by it.
            if !(pq > 0.0 && pq.is_finite() && rz.is_finite()) {
                breakdown = Some(format!(
                    "CG breakdown at iteration {iterations}: pᵀMp = {pq:.3e} (operator singular or ill-conditioned)"
                ));
                break;
            }
            let alpha = rz / pq;
            let (rr, rz_new) = cg_update(alpha, &p, &q, &inv_diag, x, &mut r, &mut z);
            iterations += 1;
            if rr.sqrt() <= target {
                break;
            }
            let beta = rz_new / rz;
            rz = rz_new;
            for_each_mut(&mut p, |i, v| *v = z[i] + beta * *v);
        }
        if let Some(msg) = breakdown {
            op.apply(x, &mut q, &mut scratch, extra);
            for_each_mut(&mut r, |i, v| *v = rhs[i] - q[i]);
            let r_norm = norm(&r);
            let rel = if rhs_norm > 0.0 {
                r_norm / rhs_norm
            } else {
                r_norm
            };
            return CgOutcome {
                iterations,
                relative_residual: rel,
                converged: r_norm <= target,
                diagnostic: Some(msg),
            };
        }
    }
}
