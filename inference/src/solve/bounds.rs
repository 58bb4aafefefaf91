//! Bounds on a premultiplied layer's texels: the penalty
//! w Σ (min(x, 0)² + max(x − hi, 0)²), zero inside [0, hi], minimized by
//! active sets. Each round fixes which texels lie outside, which makes the
//! penalty quadratic (w on the diagonal, w·hi on the right-hand side for
//! texels above hi), and solves that system by CG from the last x; it stops
//! when the set no longer changes. The least-squares solve alone lets
//! texels no view pins down alternate far outside the range (a local
//! layer's α from −1.5 to 2.1), which plays back as speckle.

use super::cg::{CgOutcome, pcg};
use super::operator::Operator;

/// Active-set rounds at most; the set settles in a few.
const MAX_ROUNDS: u32 = 8;

/// The penalty's weight and upper bound, and CG's stopping rule.
pub(crate) struct Bounds {
    pub weight: f64,
    pub hi: f64,
    pub tolerance: f64,
    pub max_iterations: u32,
}

/// Continues from `first` (the unbounded solve that left `x`) until the set
/// of texels outside [0, hi] settles. Iterations add up over rounds.
pub(crate) fn refine(
    op: &Operator,
    rhs: &[f64],
    x: &mut [f64],
    bounds: &Bounds,
    first: CgOutcome,
) -> CgOutcome {
    let Bounds {
        weight,
        hi,
        tolerance,
        max_iterations,
    } = *bounds;
    let side = |v: f64| (v > hi) as i8 - (v < 0.0) as i8;
    let mut active = vec![0i8; x.len()];
    let mut out = first;
    for _ in 0..MAX_ROUNDS {
        let next: Vec<i8> = x.iter().map(|&v| side(v)).collect();
        if next == active {
            break;
        }
        active = next;
        let diag: Vec<f64> = active.iter().map(|&a| weight * a.abs() as f64).collect();
        let shifted: Vec<f64> = rhs
            .iter()
            .zip(&active)
            .map(|(&r, &a)| if a > 0 { r + weight * hi } else { r })
            .collect();
        let budget = max_iterations.saturating_sub(out.iterations).max(1);
        let round = pcg(op, Some(&diag), &shifted, x, tolerance, budget);
        out = CgOutcome {
            iterations: out.iterations + round.iterations,
            ..round
        };
    }
    out
}
