//! Least-squares texture inference (Hakura's thesis ch. 3, papers.md §1).
//!
//! Unknown `x`: every texel of one channel of a MIP pyramid (2D or cube),
//! ordered by [`TextureLayout`]. Rendering is `A x` ([`CsrMatrix`], rows =
//! visible pixels, entries = filter weights). [`solve`] minimizes
//!
//! ```text
//! ‖A x − b‖² + ε_f (n_s/n_t) Γ(x) + ε_b (n_s/n_t) s² / (g(0) − g(½)) Σ g(x_i / s)
//! ```
//!
//! - Γ ([`pyramid`]): Σ over levels l < last of ‖level_l − bilinear
//!   upsample(level_{l+1})‖², per face, clamped at face edges (cube faces
//!   are not coupled across seams). Quadratic: folded into the CG operator
//!   as matrix-free stencils. Optional, not in the thesis: a seam term
//!   `ε_seam (n_s/n_t) Σ (x_i − x_j)²` over texels adjacent across cube face
//!   edges ([`seams`], off by default).
//! - The quadratic part is solved by Jacobi-preconditioned CG on the normal
//!   equations `(AᵀA + λ_f PᵀP) x = Aᵀb`, using products with A and Aᵀ
//!   ([`Form::A`]) or the stored sparse AᵀA ([`Form::NormalMatrix`]); AᵀA
//!   when `2 n_s ≥ K n_t`. Stopping: relative residual of those equations.
//! - The range barrier g ([`range`], off when ε_b = 0) is non-quadratic:
//!   damped Newton steps, each solved by the same PCG, from the clamped
//!   quadratic solution. s = 1 for [0,1] data; for HDR, s = `range_max` or
//!   max(b), and the s² factor (1 for LDR, as in the thesis) keeps the
//!   barrier's weight relative to the data term, so the solve is scale-free.
//! - Texels no pixel influences are defined by Γ alone. Without the seam
//!   term, if a whole cube face (or, with a truncated chain, a top-level
//!   texel's whole footprint) is unseen, the operator is singular there and
//!   CG keeps that component at the start value: 0 cold, the neighbour's
//!   value when warm-started (the solution's diagnostic names such faces).
//! - All products and reductions sum in a fixed order: results are
//!   bit-identical for any rayon thread count.

mod bounds;
mod cg;
pub mod csr;
mod error;
pub mod layout;
mod newton;
mod operator;
mod options;
pub mod pyramid;
mod pyramid_op;
pub mod range;
mod row_sums;
pub mod seams;
mod solver;
mod vecops;

#[cfg(test)]
mod tests;

pub use csr::{CsrBuilder, CsrMatrix, Scalar};
pub use error::SolveError;
pub use layout::{TextureLayout, TextureShape};
pub use options::{Form, Solution, SolveOptions};
pub use row_sums::correct_row_sums;
pub use solver::{Solver, solve, solve_channels};
