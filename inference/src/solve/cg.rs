//! Jacobi-preconditioned conjugate gradient on the SPD (or PSD) operator.
//!
//! State is f64 so a 1e-4 … 1e-6 relative residual is reachable with f32
//! matrices. Convergence is judged on the true residual: when the recurrence
//! says "done", the residual is recomputed and CG restarts from there if
//! drift fooled it. Every loop is bounded by `max_iterations`.

use super::operator::{Operator, Scratch};
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
    let rhs_norm = norm(rhs);
    let target = tolerance * rhs_norm;
    let relative = |r_norm: f64| {
        if rhs_norm > 0.0 {
            r_norm / rhs_norm
        } else {
            r_norm
        }
    };
    let mut cg = Cg::new(op, extra, rhs);
    loop {
        let r_norm = cg.true_residual(x);
        let rel = relative(r_norm);
        let done = |converged, diagnostic| CgOutcome {
            iterations: cg.iterations,
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
        if cg.iterations >= max_iterations {
            return done(
                false,
                Some(format!(
                    "stopped at max_iterations = {max_iterations} with relative residual {rel:.3e} > tolerance {tolerance:.1e}"
                )),
            );
        }
        if let Err(breakdown) = cg.run(x, target, max_iterations) {
            let r_norm = cg.true_residual(x);
            return CgOutcome {
                iterations: cg.iterations,
                relative_residual: relative(r_norm),
                converged: r_norm <= target,
                diagnostic: Some(breakdown),
            };
        }
    }
}

/// The operator, its Jacobi preconditioner and the CG vectors, kept across
/// restarts.
struct Cg<'a> {
    op: &'a Operator<'a>,
    extra: Option<&'a [f64]>,
    rhs: &'a [f64],
    /// 1 / diag(M + diag(extra)).
    inv_diag: Vec<f64>,
    scratch: Scratch,
    /// Residual, preconditioned residual, search direction, M p.
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    /// Iterations so far, over all restarts.
    iterations: u32,
}

impl<'a> Cg<'a> {
    fn new(op: &'a Operator<'a>, extra: Option<&'a [f64]>, rhs: &'a [f64]) -> Self {
        let n = rhs.len();
        Self {
            op,
            extra,
            rhs,
            inv_diag: jacobi_inverse(op, extra, n),
            scratch: op.scratch(),
            r: vec![0.0; n],
            z: vec![0.0; n],
            p: vec![0.0; n],
            q: vec![0.0; n],
            iterations: 0,
        }
    }

    /// r = rhs − (M + diag(extra)) x; returns ‖r‖.
    fn true_residual(&mut self, x: &[f64]) -> f64 {
        self.op.apply(x, &mut self.q, &mut self.scratch, self.extra);
        let (rhs, q) = (self.rhs, &self.q);
        for_each_mut(&mut self.r, |i, v| *v = rhs[i] - q[i]);
        norm(&self.r)
    }

    /// CG from `x` and its residual in `r` until the recurrence's residual
    /// reaches `target` or `max_iterations` is spent. Errs with a message
    /// if the operator breaks down (pᵀMp not positive and finite).
    fn run(&mut self, x: &mut [f64], target: f64, max_iterations: u32) -> Result<(), String> {
        let inv_diag = &self.inv_diag;
        let r = &self.r;
        for_each_mut(&mut self.z, |i, v| *v = r[i] * inv_diag[i]);
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        while self.iterations < max_iterations {
            self.op
                .apply(&self.p, &mut self.q, &mut self.scratch, self.extra);
            let pq = dot(&self.p, &self.q);
            // pᵀMp ≤ 0 means M is not positive definite along p (singular A
            // with ε_f = 0, or rounding): stop rather than divide by it.
            if !(pq > 0.0 && pq.is_finite() && rz.is_finite()) {
                return Err(format!(
                    "CG breakdown at iteration {}: pᵀMp = {pq:.3e} (operator singular or ill-conditioned)",
                    self.iterations
                ));
            }
            let alpha = rz / pq;
            let (rr, rz_new) = cg_update(
                alpha,
                &self.p,
                &self.q,
                &self.inv_diag,
                x,
                &mut self.r,
                &mut self.z,
            );
            self.iterations += 1;
            if rr.sqrt() <= target {
                break;
            }
            let beta = rz_new / rz;
            rz = rz_new;
            let z = &self.z;
            for_each_mut(&mut self.p, |i, v| *v = z[i] + beta * *v);
        }
        Ok(())
    }
}

/// 1 / diag(M + diag(extra)). Non-positive entries (columns nothing
/// touches) get 1: those residual components stay zero, so the value only
/// has to be finite.
fn jacobi_inverse(op: &Operator, extra: Option<&[f64]>, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let d = op.diag[i] + extra.map_or(0.0, |e| e[i]);
            if d > 0.0 && d.is_finite() {
                1.0 / d
            } else {
                1.0
            }
        })
        .collect()
}
