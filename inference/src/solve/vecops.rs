//! f64 vector kernels for CG. Reductions sum fixed-size chunks and then the
//! partials in order, so results do not depend on the rayon thread count.

use rayon::prelude::*;

const CHUNK: usize = 8192;
const PAR_MIN: usize = 1 << 16;

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let part = |(x, y): (&[f64], &[f64])| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    if a.len() >= PAR_MIN {
        let parts: Vec<f64> = a
            .par_chunks(CHUNK)
            .zip(b.par_chunks(CHUNK))
            .map(part)
            .collect();
        parts.iter().sum()
    } else {
        a.chunks(CHUNK).zip(b.chunks(CHUNK)).map(part).sum()
    }
}

pub fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Applies `f(i, &mut y[i])` over all elements, in parallel when long.
pub fn for_each_mut(y: &mut [f64], f: impl Fn(usize, &mut f64) + Sync) {
    if y.len() >= PAR_MIN {
        y.par_chunks_mut(CHUNK).enumerate().for_each(|(c, ys)| {
            for (o, v) in ys.iter_mut().enumerate() {
                f(c * CHUNK + o, v);
            }
        });
    } else {
        y.iter_mut().enumerate().for_each(|(i, v)| f(i, v));
    }
}

/// y += a x
pub fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for_each_mut(y, |i, v| *v += a * x[i]);
}
