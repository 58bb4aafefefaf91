//! The regularized solve: validation, form choice, PCG, optional Newton
//! refinement for the range term, and the multi-channel helper.

use rayon::prelude::*;

use super::SolveError;
use super::cg::{CgOutcome, pcg};
use super::csr::CsrMatrix;
use super::layout::TextureLayout;
use super::operator::{Form, Operator, Pyramid, Seams};
use super::options::{Solution, SolveOptions};
use super::pyramid_op::PyramidOperator;
use super::range::calibration;
use super::seams::seam_matrix;
use super::{bounds, newton};

/// A prepared system for one A: reuse it for every channel (and for any
/// number of right-hand sides) of that A.
pub struct Solver<'a> {
    op: Operator<'a>,
    a: &'a CsrMatrix,
    options: SolveOptions,
    /// ε_b (n_s/n_t) / (g(0) − g(½)).
    lambda_b: f64,
    /// Cube faces no nonzero of A touches (at any level): without the seam
    /// term nothing couples faces, so these keep their start value.
    unseen_faces: Vec<u32>,
}

/// Faces of `layout` whose texels (all levels) are columns A never uses.
fn unseen_faces(a: &CsrMatrix, layout: &TextureLayout) -> Vec<u32> {
    if layout.faces() == 1 {
        return Vec::new();
    }
    let mut seen = vec![false; layout.faces() as usize];
    for &c in &a.col_idx {
        seen[layout.coords(c as usize).0 as usize] = true;
    }
    (0..layout.faces()).filter(|&f| !seen[f as usize]).collect()
}

fn check_finite(what: &'static str, v: &[f32]) -> Result<(), SolveError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(SolveError::NonFinite { what, index }),
        None => Ok(()),
    }
}

fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), SolveError> {
    if expected == found {
        Ok(())
    } else {
        Err(SolveError::DimensionMismatch {
            what,
            expected,
            found,
        })
    }
}

impl<'a> Solver<'a> {
    /// Validates A (structure, finiteness) and the options, picks the form
    /// (AᵀA when 2 n_s ≥ K n_t unless forced) and builds its matrices.
    pub fn new(
        a: &'a CsrMatrix,
        layout: &TextureLayout,
        options: &SolveOptions,
    ) -> Result<Self, SolveError> {
        options.validate()?;
        a.validate("A values")?;
        check_len("A columns (texels of the layout)", layout.len(), a.cols)?;
        let (n_s, n_t) = (a.rows as f64, a.cols as f64);
        let ratio = if a.cols > 0 { n_s / n_t } else { 0.0 };
        let lambda_f = options.eps_f as f64 * ratio;
        let form = options
            .force_form
            .unwrap_or(if 2.0 * n_s >= options.k_switch as f64 * n_t {
                Form::NormalMatrix
            } else {
                Form::A
            });
        let reg = (lambda_f > 0.0).then(|| Pyramid {
            lambda: lambda_f,
            p: PyramidOperator::new(layout),
        });
        let lambda_seam = options.eps_seam as f64 * ratio;
        let seams = (lambda_seam > 0.0 && layout.faces() == 6).then(|| Seams {
            lambda: lambda_seam,
            s: seam_matrix(layout),
        });
        let prior = f64::from(options.eps_prior);
        let unseen = if seams.is_some() || prior > 0.0 {
            Vec::new()
        } else {
            unseen_faces(a, layout)
        };
        Ok(Self {
            op: Operator::new(a, reg, seams, prior, form),
            a,
            options: options.clone(),
            lambda_b: options.eps_b as f64 * ratio * calibration(),
            unseen_faces: unseen,
        })
    }

    pub fn form(&self) -> Form {
        self.op.form()
    }

    /// Solves one channel. `x0` is the warm start (e.g. the neighbouring
    /// parameter sample's solution).
    pub fn solve(&self, b: &[f32], x0: Option<&[f32]>) -> Result<Solution, SolveError> {
        self.solve_within(b, x0, f64::INFINITY)
    }

    /// [`Solver::solve`] with `upper` as the channel's upper bound when
    /// `eps_bound` > 0 (its lower bound is 0).
    pub fn solve_within(
        &self,
        b: &[f32],
        x0: Option<&[f32]>,
        upper: f64,
    ) -> Result<Solution, SolveError> {
        self.check_inputs(b, x0)?;
        let n_t = self.a.cols;
        if self.a.rows == 0 || self.a.nnz() == 0 {
            let why = "A has no nonzeros (the object covers no pixel): nothing to fit";
            return Ok(match x0 {
                Some(x0) => self.trivial(x0.to_vec(), format!("{why}; returning x0")),
                None => self.trivial(vec![0.0; n_t], format!("{why}; returning zeros")),
            });
        }
        let bd: Vec<f64> = b.iter().map(|&v| v as f64).collect();
        let mut rhs = vec![0.0f64; n_t];
        self.a.mul_transpose(&bd, &mut rhs);
        if rhs.iter().all(|&v| v == 0.0) {
            let why = "Aᵀb = 0 (all-zero layer): x = 0";
            return Ok(self.trivial(vec![0.0; n_t], why.into()));
        }
        let mut x: Vec<f64> = match x0 {
            Some(x0) => x0.iter().map(|&v| v as f64).collect(),
            None => vec![0.0; n_t],
        };
        let tol = self.options.tolerance as f64;
        let max_it = self.options.max_iterations;
        let mut out = pcg(&self.op, None, &rhs, &mut x, tol, max_it);
        let weight = f64::from(self.options.eps_bound);
        if weight > 0.0 {
            let b = bounds::Bounds {
                weight,
                hi: upper,
                tolerance: tol,
                max_iterations: max_it,
            };
            out = bounds::refine(&self.op, &rhs, &mut x, &b, out);
        }
        if self.lambda_b > 0.0 {
            out = self.refine_range(b, &rhs, &mut x, out);
        }
        Ok(Solution {
            x: x.iter().map(|&v| v as f32).collect(),
            iterations: out.iterations,
            relative_residual: out.relative_residual as f32,
            converged: out.converged,
            form: self.form(),
            diagnostic: self.note_unseen_faces(out.diagnostic, x0.is_some()),
        })
    }

    /// b and x0 match A's dimensions and are finite.
    fn check_inputs(&self, b: &[f32], x0: Option<&[f32]>) -> Result<(), SolveError> {
        check_len("b (rows of A)", self.a.rows, b.len())?;
        check_finite("b", b)?;
        if let Some(x0) = x0 {
            check_len("x0 (columns of A)", self.a.cols, x0.len())?;
            check_finite("x0", x0)?;
        }
        Ok(())
    }

    /// A result that needed no iterations, with the reason.
    fn trivial(&self, x: Vec<f32>, why: String) -> Solution {
        Solution {
            x,
            iterations: 0,
            relative_residual: 0.0,
            converged: true,
            form: self.form(),
            diagnostic: Some(why),
        }
    }

    /// Newton refinement for the range term, continuing from the quadratic
    /// solution `quadratic`. The texel range is [0, s], s = `range_max` or
    /// max(b) (1 if b has no positive value). If the refinement fails
    /// without saying why, the quadratic solve's note is kept.
    fn refine_range(
        &self,
        b: &[f32],
        rhs: &[f64],
        x: &mut [f64],
        mut quadratic: CgOutcome,
    ) -> CgOutcome {
        let bmax = b.iter().fold(0.0f32, |m, &v| m.max(v));
        let s = self
            .options
            .range_max
            .unwrap_or(if bmax > 0.0 { bmax } else { 1.0 }) as f64;
        let quad_note = quadratic.diagnostic.take();
        let term = newton::RangeTerm {
            lambda_b: self.lambda_b,
            s,
            tolerance: self.options.tolerance as f64,
            max_iterations: self.options.max_iterations,
        };
        let mut out = newton::refine(&self.op, rhs, x, &term, quadratic.iterations);
        if out.diagnostic.is_none() && !out.converged {
            out.diagnostic = quad_note;
        }
        out
    }

    /// Appends the names of unseen cube faces (kept at the start value:
    /// x0 when `warm`, else 0) to `diagnostic`.
    fn note_unseen_faces(&self, diagnostic: Option<String>, warm: bool) -> Option<String> {
        if self.unseen_faces.is_empty() {
            return diagnostic;
        }
        let note = format!(
            "cube faces {:?} are seen by no pixel: kept at the start value ({})",
            self.unseen_faces,
            if warm { "x0" } else { "0" }
        );
        Some(match diagnostic {
            Some(d) => format!("{d}; {note}"),
            None => note,
        })
    }
}

/// Minimizes ‖A x − b‖² + ε_f (n_s/n_t) Γ(x) [+ ε_b range term] for one
/// channel. See [`Solver`] to reuse the prepared system.
pub fn solve(
    a: &CsrMatrix,
    b: &[f32],
    layout: &TextureLayout,
    x0: Option<&[f32]>,
    options: &SolveOptions,
) -> Result<Solution, SolveError> {
    Solver::new(a, layout, options)?.solve(b, x0)
}

/// The upper bound of channel `i` of `n` under `eps_bound`: α (the fourth
/// of four, premultiplied RGBA) ≤ 1, colours unbounded above.
fn channel_upper(i: usize, n: usize) -> f64 {
    if n == 4 && i == 3 { 1.0 } else { f64::INFINITY }
}

/// Several right-hand sides (e.g. R, G, B, A) with one A, prepared once and
/// solved in parallel; with `eps_bound` > 0 the fourth of four is α.
pub fn solve_channels(
    a: &CsrMatrix,
    bs: &[&[f32]],
    layout: &TextureLayout,
    x0s: Option<&[&[f32]]>,
    options: &SolveOptions,
) -> Result<Vec<Solution>, SolveError> {
    if let Some(x0s) = x0s {
        check_len("x0s (one warm start per channel)", bs.len(), x0s.len())?;
    }
    let solver = Solver::new(a, layout, options)?;
    bs.par_iter()
        .enumerate()
        .map(|(i, b)| solver.solve_within(b, x0s.map(|v| v[i]), channel_upper(i, bs.len())))
        .collect()
}
