//! Solver options and results.

use super::SolveError;
pub use super::operator::Form;

/// Weights and stopping rule of the regularized least-squares solve.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveOptions {
    /// Pyramidal regularization weight ε_f (thesis: 0.1).
    pub eps_f: f32,
    /// Cube maps only: weight of the seam term Σ (x_i − x_j)² over texels
    /// adjacent across face edges, scaled by n_s/n_t like ε_f. Not in the
    /// thesis; 0 (default) leaves faces independent. > 0 fills unseen faces
    /// from their neighbours and makes the system SPD once any texel is seen.
    pub eps_seam: f32,
    /// Weight of a prior toward zero, Σ x_i² (absolute, not scaled by
    /// n_s/n_t): for a premultiplied RGBA layer, zero is "transparent", so
    /// texels no view constrains stay see-through instead of taking what
    /// the pyramid term spreads into them. 0 (default) = off.
    pub eps_prior: f32,
    /// Premultiplied RGBA layers: weight of a penalty on texels outside
    /// their range (every channel ≥ 0, the fourth, α, ≤ 1), zero inside it
    /// (absolute, like `eps_prior`), solved by active sets. Unlike the
    /// barrier of `eps_b` it leaves transparent texels at 0. 0 (default) = off.
    pub eps_bound: f32,
    /// Range regularization weight ε_b (0 = off; thesis figures used 1/32).
    pub eps_b: f32,
    /// Texel range for the range term: [0, range_max]; the barrier is
    /// weighted by range_max² so that scaling b and the range together
    /// scales x. `None` = max of b (1 if b has no positive value); pass
    /// `Some(1.0)` for the thesis' fixed [0, 1] range.
    pub range_max: Option<f32>,
    /// Use AᵀA when 2 n_s ≥ K n_t (thesis: K = 4).
    pub k_switch: f32,
    /// Force a form instead of the K heuristic (benchmarks, tests).
    pub force_form: Option<Form>,
    /// Cap on CG iterations (summed over Newton steps with the range term).
    pub max_iterations: u32,
    /// Target relative residual ‖Aᵀb − M x‖ / ‖Aᵀb‖ of the normal equations
    /// (gradient norm relative to ‖Aᵀb‖ with the range term).
    pub tolerance: f32,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            eps_f: 0.1,
            eps_seam: 0.0,
            eps_prior: 0.0,
            eps_bound: 0.0,
            eps_b: 0.0,
            range_max: None,
            k_switch: 4.0,
            force_form: None,
            max_iterations: 2000,
            tolerance: 1e-4,
        }
    }
}

impl SolveOptions {
    pub fn validate(&self) -> Result<(), SolveError> {
        let check = |name, value: f32, ok: bool, reason| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(SolveError::InvalidOption {
                    name,
                    value: value as f64,
                    reason,
                })
            }
        };
        check(
            "eps_f",
            self.eps_f,
            self.eps_f >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "eps_b",
            self.eps_b,
            self.eps_b >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "eps_prior",
            self.eps_prior,
            self.eps_prior >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "eps_bound",
            self.eps_bound,
            self.eps_bound >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "eps_seam",
            self.eps_seam,
            self.eps_seam >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "k_switch",
            self.k_switch,
            self.k_switch > 0.0,
            "must be finite and > 0",
        )?;
        check(
            "tolerance",
            self.tolerance,
            self.tolerance >= 0.0,
            "must be finite and >= 0",
        )?;
        if let Some(m) = self.range_max {
            check("range_max", m, m > 0.0, "must be finite and > 0")?;
        }
        Ok(())
    }
}

/// One channel's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    pub x: Vec<f32>,
    /// CG iterations performed (all Newton steps together).
    pub iterations: u32,
    pub relative_residual: f32,
    pub converged: bool,
    pub form: Form,
    /// Why the result is special (empty A, zero layer, breakdown, cap hit).
    pub diagnostic: Option<String>,
}
