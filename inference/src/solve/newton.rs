//! Range term by damped Newton around PCG: the objective (halved)
//! F(x) = ½xᵀMx − rhsᵀx + ½λ_b s² Σ g(x_i/s) is strictly convex on the box
//! (−δ s, (1+δ) s), so Newton steps (M + diag(½λ_b g″)) Δ = −∇F solved
//! inexactly by PCG, with a backtracking line search that stays inside the
//! box and decreases F, converge to the unique minimizer.

use super::cg::{CgOutcome, pcg};
use super::operator::{Operator, Scratch};
use super::range::{RANGE_DELTA, g, g_derivatives};
use super::vecops::{dot, for_each_mut, norm};

const MAX_NEWTON: u32 = 40;
/// Inexact-Newton forcing term: each step's CG stops at 10% of ‖∇F‖.
const FORCING: f64 = 0.1;
/// Halvings of the step length before the line search gives up.
const MAX_BACKTRACKS: u32 = 60;
/// Armijo constant: a step must achieve this fraction of the predicted decrease.
const ARMIJO: f64 = 1e-4;

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
    let rhs_norm = norm(rhs);
    // The barrier acts on x/s; weighting it by s² too makes the whole
    // objective scale by s² when b and the range do, so an HDR layer solved
    // with s = max(b) gives exactly the LDR answer times s.
    let f = Objective {
        op,
        rhs,
        w: 0.5 * lambda_b * s * s,
        s,
    };
    for_each_mut(x, |_, v| *v = v.clamp(0.0, s));
    let mut ws = Workspace::new(op, x.len());
    let mut iterations = iterations_used;
    let mut rel = f64::INFINITY;
    for _ in 0..MAX_NEWTON {
        rel = f.gradient(x, &mut ws) / rhs_norm;
        let stop = |iterations, diagnostic| outcome(iterations, rel, diagnostic);
        if !rel.is_finite() {
            let why = "range term: gradient became non-finite";
            return stop(iterations, Some(why.into()));
        }
        if rel <= tolerance {
            return stop(iterations, None);
        }
        if iterations >= max_iterations {
            let why = format!(
                "range term: max_iterations = {max_iterations} reached at gradient {rel:.3e}"
            );
            return stop(iterations, Some(why));
        }
        let (inner, taken) = f.newton_step(x, &mut ws, max_iterations - iterations);
        iterations += inner;
        if let Err(failure) = taken {
            return stop(iterations, Some(failure.diagnostic(rel)));
        }
    }
    let why = format!("range term: {MAX_NEWTON} Newton steps without reaching the tolerance");
    outcome(iterations, rel, Some(why))
}

/// Converged exactly when there is nothing to report.
fn outcome(iterations: u32, relative_residual: f64, diagnostic: Option<String>) -> CgOutcome {
    CgOutcome {
        iterations,
        relative_residual,
        converged: diagnostic.is_none(),
        diagnostic,
    }
}

/// Why a Newton step could not be taken.
enum StepFailure {
    /// ∇F·Δ ≥ 0 (or NaN): the inexact solve gave no descent direction.
    NotDescent { slope: f64 },
    /// No step length along Δ decreased F enough.
    LineSearch,
}

impl StepFailure {
    fn diagnostic(&self, rel: f64) -> String {
        match self {
            StepFailure::NotDescent { slope } => {
                format!("range term: Newton step is not a descent direction ({slope:.3e})")
            }
            StepFailure::LineSearch => {
                format!("range term: line search failed at gradient {rel:.3e}")
            }
        }
    }
}

/// F's pieces: M (through `op`), the right-hand side, and the barrier
/// g(x/s) with its weight `w` = ½λ_b s².
struct Objective<'a> {
    op: &'a Operator<'a>,
    rhs: &'a [f64],
    w: f64,
    s: f64,
}

/// Vectors reused across Newton steps.
struct Workspace {
    scratch: Scratch,
    /// M x.
    mx: Vec<f64>,
    /// ∇F at x.
    grad: Vec<f64>,
    /// The barrier's Hessian diagonal, w/s² g″(x/s).
    hessian: Vec<f64>,
    /// Newton direction Δ.
    step: Vec<f64>,
    /// M Δ.
    mstep: Vec<f64>,
    /// −∇F while solving for Δ, then the line search's trial point.
    trial: Vec<f64>,
}

impl Workspace {
    fn new(op: &Operator, n: usize) -> Self {
        Self {
            scratch: op.scratch(),
            mx: vec![0.0; n],
            grad: vec![0.0; n],
            hessian: vec![0.0; n],
            step: vec![0.0; n],
            mstep: vec![0.0; n],
            trial: vec![0.0; n],
        }
    }
}

/// F along x + αΔ, as F(x + αΔ) − F(x) =
/// α `quad_slope` + ½α² `curvature` + w (B(x + αΔ) − B(x)), B = Σ g(x_i/s).
struct Ray {
    /// ∇F·Δ (negative: Δ descends).
    slope: f64,
    /// (M x − rhs)·Δ: the quadratic part's share of `slope`.
    quad_slope: f64,
    /// Δᵀ M Δ.
    curvature: f64,
}

impl Objective<'_> {
    /// Fills `ws.grad` with ∇F(x) (and `ws.mx` with M x); returns ‖∇F‖.
    fn gradient(&self, x: &[f64], ws: &mut Workspace) -> f64 {
        let (w, s, rhs) = (self.w, self.s, self.rhs);
        self.op.apply(x, &mut ws.mx, &mut ws.scratch, None);
        let mx = &ws.mx;
        for_each_mut(&mut ws.grad, |i, v| {
            *v = mx[i] - rhs[i] + w / s * g_derivatives(x[i] / s).0;
        });
        norm(&ws.grad)
    }

    /// One damped Newton step from `x`, whose gradient is in `ws.grad`:
    /// Δ from PCG with at most `budget` iterations, then x moves along Δ by
    /// the line search. Returns the CG iterations spent, and whether the
    /// step was taken (x is unchanged if not).
    fn newton_step(
        &self,
        x: &mut [f64],
        ws: &mut Workspace,
        budget: u32,
    ) -> (u32, Result<(), StepFailure>) {
        let inner = self.newton_direction(x, ws, budget);
        let slope = dot(&ws.grad, &ws.step);
        if slope.is_nan() || slope >= 0.0 {
            return (inner, Err(StepFailure::NotDescent { slope }));
        }
        let ray = self.ray(x, ws, slope);
        if !self.line_search(x, ws, &ray) {
            return (inner, Err(StepFailure::LineSearch));
        }
        x.copy_from_slice(&ws.trial);
        (inner, Ok(()))
    }

    /// Solves (M + diag(w/s² g″)) Δ = −∇F into `ws.step` by PCG from Δ = 0,
    /// stopping at `FORCING` relative residual; returns the iterations.
    fn newton_direction(&self, x: &[f64], ws: &mut Workspace, budget: u32) -> u32 {
        let (w, s) = (self.w, self.s);
        for_each_mut(&mut ws.hessian, |i, v| {
            *v = w / (s * s) * g_derivatives(x[i] / s).1
        });
        let grad = &ws.grad;
        for_each_mut(&mut ws.trial, |i, v| *v = -grad[i]);
        ws.step.iter_mut().for_each(|v| *v = 0.0);
        let out = pcg(
            self.op,
            Some(&ws.hessian),
            &ws.trial,
            &mut ws.step,
            FORCING,
            budget,
        );
        out.iterations
    }

    /// F along x + αΔ (Δ in `ws.step`), from one more product with M.
    fn ray(&self, x: &[f64], ws: &mut Workspace, slope: f64) -> Ray {
        self.op
            .apply(&ws.step, &mut ws.mstep, &mut ws.scratch, None);
        let curvature = dot(&ws.step, &ws.mstep);
        let quad_slope = slope - self.w / self.s * dot_barrier_grad(x, &ws.step, self.s);
        Ray {
            slope,
            quad_slope,
            curvature,
        }
    }

    /// Backtracking from the longest step that stays inside the box until
    /// F decreases by the Armijo fraction of the predicted decrease. On
    /// success the accepted point is in `ws.trial`.
    fn line_search(&self, x: &[f64], ws: &mut Workspace, ray: &Ray) -> bool {
        let (w, s) = (self.w, self.s);
        let step = &ws.step;
        let mut alpha = max_step_inside_box(x, step, s);
        let b0 = barrier(x, s);
        for _ in 0..MAX_BACKTRACKS {
            for_each_mut(&mut ws.trial, |i, v| *v = x[i] + alpha * step[i]);
            let change = alpha * ray.quad_slope
                + 0.5 * alpha * alpha * ray.curvature
                + w * (barrier(&ws.trial, s) - b0);
            if change.is_finite() && change <= ARMIJO * alpha * ray.slope {
                return true;
            }
            alpha *= 0.5;
        }
        false
    }
}

/// Largest step length (≤ 1) keeping every texel strictly inside
/// (−δ s, (1+δ) s), with a 1% margin.
fn max_step_inside_box(x: &[f64], step: &[f64], s: f64) -> f64 {
    let mut alpha: f64 = 1.0;
    for (xi, di) in x.iter().zip(step) {
        let room = if *di > 0.0 {
            ((1.0 + RANGE_DELTA) * s - xi) / di
        } else if *di < 0.0 {
            (-RANGE_DELTA * s - xi) / di
        } else {
            f64::INFINITY
        };
        alpha = alpha.min(0.99 * room);
    }
    alpha
}

/// Σ g′(x_i/s) Δ_i: the barrier's share of ∇F·Δ (divided by w/s).
fn dot_barrier_grad(x: &[f64], step: &[f64], s: f64) -> f64 {
    x.iter()
        .zip(step)
        .map(|(&v, &d)| g_derivatives(v / s).0 * d)
        .sum()
}
