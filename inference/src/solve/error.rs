//! Errors of the least-squares texture solver.

/// Why a solve (or building its inputs) was refused. Every variant names what
/// was wrong and, where it applies, where and what was expected.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SolveError {
    /// Two sizes that must agree do not (e.g. `b` vs the rows of `A`).
    #[error("dimension mismatch: {what} has length {found}, expected {expected}")]
    DimensionMismatch {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    /// A NaN or infinity in an input (`what` = "A values", "b", "x0", ...).
    #[error("non-finite value in {what} at index {index}")]
    NonFinite { what: &'static str, index: usize },
    /// A sparse matrix whose structure is inconsistent.
    #[error("malformed CSR matrix: {reason}")]
    MalformedMatrix { reason: String },
    /// A column index beyond the matrix width.
    #[error("column {col} in row {row} is out of range (matrix has {cols} columns)")]
    ColumnOutOfRange { row: usize, col: u64, cols: usize },
    /// A texture shape or level count the layout cannot represent.
    #[error("invalid texture layout: {reason}")]
    InvalidLayout { reason: String },
    /// A solver option outside its domain.
    #[error("invalid option {name} = {value}: {reason}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
}
