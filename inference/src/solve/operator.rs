//! The SPD operator of the normal equations,
//! M = AᵀA + λ_f PᵀP (+ a diagonal from the range term's Newton steps),
//! in either form of thesis §3.5: products with A and Aᵀ (cost ∝ n_s) or
//! with the precomputed sparse AᵀA + λ_f PᵀP (cost ∝ n_t).

use super::csr::CsrMatrix;
use super::vecops::for_each_mut;

/// Which products the CG inner loop performs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Form {
    /// `Aᵀ(A v)` (+ `λ_f PᵀP v`): two sparse products of n_s rows.
    A,
    /// One product with the stored `AᵀA + λ_f PᵀP`.
    NormalMatrix,
}

pub(crate) enum Prepared<'a> {
    A {
        a: &'a CsrMatrix,
        at: CsrMatrix,
        /// λ_f PᵀP, absent when λ_f = 0.
        reg: Option<CsrMatrix>,
    },
    Normal {
        n: CsrMatrix,
    },
}

pub(crate) struct Operator<'a> {
    pub prepared: Prepared<'a>,
    /// diag(M), the Jacobi preconditioner's base.
    pub diag: Vec<f64>,
}

impl<'a> Operator<'a> {
    /// `reg` is λ_f PᵀP (or None).
    pub fn new(a: &'a CsrMatrix, reg: Option<CsrMatrix>, form: Form) -> Self {
        let at = a.transpose();
        let mut diag = a.column_sq_norms();
        if let Some(r) = &reg {
            for (d, rd) in diag.iter_mut().zip(r.diagonal()) {
                *d += rd;
            }
        }
        let prepared = match form {
            Form::A => Prepared::A { a, at, reg },
            Form::NormalMatrix => {
                let ata = a.gram_with_transpose(&at);
                drop(at);
                let n = match &reg {
                    Some(r) => ata.add_scaled(r, 1.0),
                    None => ata,
                };
                Prepared::Normal { n }
            }
        };
        Self { prepared, diag }
    }

    pub fn form(&self) -> Form {
        match self.prepared {
            Prepared::A { .. } => Form::A,
            Prepared::Normal { .. } => Form::NormalMatrix,
        }
    }

    pub fn rows_scratch(&self) -> usize {
        match &self.prepared {
            Prepared::A { a, .. } => a.rows,
            Prepared::Normal { .. } => 0,
        }
    }

    /// out = (M + diag(extra)) v; `scratch` has `rows_scratch()` elements.
    pub fn apply(&self, v: &[f64], out: &mut [f64], scratch: &mut [f64], extra: Option<&[f64]>) {
        match &self.prepared {
            Prepared::A { a, at, reg } => {
                a.mul(v, scratch);
                at.mul(scratch, out);
                if let Some(r) = reg {
                    r.mul_acc(v, out);
                }
            }
            Prepared::Normal { n } => n.mul(v, out),
        }
        if let Some(e) = extra {
            for_each_mut(out, |i, o| *o += e[i] * v[i]);
        }
    }
}
