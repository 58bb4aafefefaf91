//! The SPD operator of the normal equations,
//! M = AᵀA + λ_f PᵀP (+ a diagonal from the range term's Newton steps),
//! in either form of thesis §3.5: products with A and Aᵀ (cost ∝ n_s) or
//! with the precomputed sparse AᵀA (cost ∝ n_t).
//!
//! The pyramid term is applied as Pᵀ(P v) in both forms with matrix-free
//! stencils: P has ≤ 5 entries per row, while PᵀP couples each texel with
//! ~25–50 others (every finer texel that upsamples from it).

use super::csr::CsrMatrix;
use super::pyramid_op::PyramidOperator;
use super::vecops::for_each_mut;

/// Which products the CG inner loop performs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Form {
    /// `Aᵀ(A v)`: two sparse products over the n_s screen rows.
    A,
    /// One product with the stored `AᵀA` (n_t rows).
    NormalMatrix,
}

pub(crate) enum Data<'a> {
    A { a: &'a CsrMatrix, at: CsrMatrix },
    Normal { n: CsrMatrix },
}

/// λ_f and the (matrix-free) P of the pyramid term.
pub(crate) struct Pyramid {
    pub lambda: f64,
    pub p: PyramidOperator,
}

/// λ_seam and the seam-difference matrix S (cube maps, optional).
pub(crate) struct Seams {
    pub lambda: f64,
    pub s: CsrMatrix,
}

pub(crate) struct Operator<'a> {
    data: Data<'a>,
    reg: Option<Pyramid>,
    seams: Option<Seams>,
    /// λ of the prior toward zero (adds λ I).
    prior: f64,
    /// diag(M), the Jacobi preconditioner's base.
    pub diag: Vec<f64>,
}

/// Per-solve temporaries (one per parallel channel).
pub(crate) struct Scratch {
    screen: Vec<f64>,
    pyramid: Vec<f64>,
    seam: Vec<f64>,
}

impl<'a> Operator<'a> {
    pub fn new(
        a: &'a CsrMatrix,
        reg: Option<Pyramid>,
        seams: Option<Seams>,
        prior: f64,
        form: Form,
    ) -> Self {
        let at = a.transpose();
        let mut diag = a.column_sq_norms();
        diag.iter_mut().for_each(|d| *d += prior);
        if let Some(r) = &reg {
            for (d, pd) in diag.iter_mut().zip(r.p.column_sq_norms()) {
                *d += r.lambda * pd;
            }
        }
        if let Some(sm) = &seams {
            for (d, sd) in diag.iter_mut().zip(sm.s.column_sq_norms()) {
                *d += sm.lambda * sd;
            }
        }
        let data = match form {
            Form::A => Data::A { a, at },
            Form::NormalMatrix => Data::Normal {
                n: a.gram_with_transpose(&at),
            },
        };
        Self {
            data,
            reg,
            seams,
            prior,
            diag,
        }
    }

    pub fn form(&self) -> Form {
        match self.data {
            Data::A { .. } => Form::A,
            Data::Normal { .. } => Form::NormalMatrix,
        }
    }

    pub fn scratch(&self) -> Scratch {
        Scratch {
            screen: match &self.data {
                Data::A { a, .. } => vec![0.0; a.rows],
                Data::Normal { .. } => Vec::new(),
            },
            pyramid: vec![0.0; self.reg.as_ref().map_or(0, |r| r.p.rows)],
            seam: vec![0.0; self.seams.as_ref().map_or(0, |sm| sm.s.rows)],
        }
    }

    /// out = (M + diag(extra)) v.
    pub fn apply(&self, v: &[f64], out: &mut [f64], s: &mut Scratch, extra: Option<&[f64]>) {
        match &self.data {
            Data::A { a, at } => {
                a.mul(v, &mut s.screen);
                at.mul(&s.screen, out);
            }
            Data::Normal { n } => n.mul(v, out),
        }
        if let Some(r) = &self.reg {
            r.p.mul(v, &mut s.pyramid);
            let l = r.lambda;
            for_each_mut(&mut s.pyramid, |_, x| *x *= l);
            r.p.mul_transpose_acc(&s.pyramid, out);
        }
        if let Some(sm) = &self.seams {
            sm.s.mul(v, &mut s.seam);
            sm.s.mul_transpose_acc(&s.seam, sm.lambda, out);
        }
        if self.prior > 0.0 {
            let l = self.prior;
            for_each_mut(out, |i, o| *o += l * v[i]);
        }
        if let Some(e) = extra {
            for_each_mut(out, |i, o| *o += e[i] * v[i]);
        }
    }
}
