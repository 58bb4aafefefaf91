//! Least-squares texture inference (Hakura's thesis ch. 3): solve
//! `min ‖A x − b‖² + ε_f (n_s/n_t) Γ(x) [+ ε_b range term]` by
//! preconditioned conjugate gradient, x = all texels of a MIP pyramid.

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
