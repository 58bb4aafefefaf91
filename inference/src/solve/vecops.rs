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

/// One fused CG pass: x += αp, r −= αq, z = r ⊙ inv_diag; returns (r·r, r·z).
/// Chunk partials are summed in order, so the result is thread-count free.
pub fn cg_update(
    alpha: f64,
    p: &[f64],
    q: &[f64],
    inv_diag: &[f64],
    x: &mut [f64],
    r: &mut [f64],
    z: &mut [f64],
) -> (f64, f64) {
    let chunk = |c: usize, (xs, (rs, zs)): (&mut [f64], (&mut [f64], &mut [f64]))| {
        let base = c * CHUNK;
        let (mut rr, mut rz) = (0.0, 0.0);
        for (o, (xi, (ri, zi))) in xs
            .iter_mut()
            .zip(rs.iter_mut().zip(zs.iter_mut()))
            .enumerate()
        {
            let i = base + o;
            *xi += alpha * p[i];
            *ri -= alpha * q[i];
            *zi = *ri * inv_diag[i];
            rr += *ri * *ri;
            rz += *ri * *zi;
        }
        (rr, rz)
    };
    let parts: Vec<(f64, f64)> = if x.len() >= PAR_MIN {
        x.par_chunks_mut(CHUNK)
            .zip(r.par_chunks_mut(CHUNK).zip(z.par_chunks_mut(CHUNK)))
            .enumerate()
            .map(|(c, t)| chunk(c, t))
            .collect()
    } else {
        x.chunks_mut(CHUNK)
            .zip(r.chunks_mut(CHUNK).zip(z.chunks_mut(CHUNK)))
            .enumerate()
            .map(|(c, t)| chunk(c, t))
            .collect()
    };
    parts
        .iter()
        .fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d))
}
