//! Row-sum correction of probed filter weights (thesis §3.4): filter weights
//! of a row should sum to one, but probes truncate tiny weights, so rows
//! summing below `expected` get the deficit spread as one constant added to
//! each of their nonzeros (the thesis' "simple correction"; its
//! line-fitting alternative is slower and not implemented).

use super::csr::CsrMatrix;

/// Returns how many rows were corrected. Rows with no nonzeros, rows at or
/// above `expected`, and non-finite sums are left alone.
pub fn correct_row_sums(a: &mut CsrMatrix, expected: f32) -> usize {
    let mut corrected = 0;
    for r in 0..a.rows {
        let (s, e) = (a.row_ptr[r], a.row_ptr[r + 1]);
        if s == e {
            continue;
        }
        let sum: f64 = a.values[s..e].iter().map(|&v| v as f64).sum();
        let deficit = expected as f64 - sum;
        if sum.is_finite() && deficit > 0.0 {
            let add = (deficit / (e - s) as f64) as f32;
            a.values[s..e].iter_mut().for_each(|v| *v += add);
            corrected += 1;
        }
    }
    corrected
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::csr::CsrBuilder;

    #[test]
    fn spreads_the_deficit_over_nonzeros_only() {
        let mut b = CsrBuilder::new(4);
        b.push_row(&[(0, 0.5), (2, 0.3)]).unwrap();
        b.push_row(&[(1, 0.6), (3, 0.4)]).unwrap();
        b.push_row(&[]).unwrap();
        b.push_row(&[(3, 1.2)]).unwrap();
        let mut a = b.finish();
        assert_eq!(correct_row_sums(&mut a, 1.0), 1);
        assert!((a.values[0] - 0.6).abs() < 1e-6 && (a.values[1] - 0.4).abs() < 1e-6);
        assert_eq!(&a.values[2..], &[0.6, 0.4, 1.2]);
        assert_eq!(a.col_idx, vec![0, 2, 1, 3, 3]);
    }
}
