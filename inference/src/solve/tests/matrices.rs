//! The sparse matrix kernels the solve is built on: products with A and
//! Aᵀ, AᵀA, the builder and vstack.

use proptest::prelude::{ProptestConfig, prop_assert, prop_assert_eq, proptest};

use super::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn transpose_products_are_adjoint_and_agree(seed: u64, rows in 0usize..30, cols in 1usize..30) {
        let mut rng = Rng(seed);
        let mut bld = CsrBuilder::new(cols);
        for _ in 0..rows {
            let k = rng.below(9) as usize;
            let row: Vec<_> = (0..k).map(|_| (rng.below(cols), rng.unit() - 0.5)).collect();
            bld.push_row(&row).unwrap();
        }
        let a = bld.finish();
        a.validate("A").unwrap();
        let x: Vec<f64> = (0..cols).map(|_| rng.unit() as f64 - 0.5).collect();
        let y: Vec<f64> = (0..rows).map(|_| rng.unit() as f64 - 0.5).collect();
        let (mut ax, mut aty, mut aty2) = (vec![0.0; rows], vec![0.0; cols], vec![0.0; cols]);
        a.mul(&x, &mut ax);
        a.mul_transpose(&y, &mut aty);
        a.transpose().mul(&y, &mut aty2);
        let lhs: f64 = ax.iter().zip(&y).map(|(p, q)| p * q).sum();
        let rhs: f64 = x.iter().zip(&aty).map(|(p, q)| p * q).sum();
        prop_assert!((lhs - rhs).abs() <= 1e-9 * (1.0 + lhs.abs()));
        prop_assert_eq!(&aty, &aty2); // same summation order, same bits
        // AᵀA against the dense product.
        let n = a.normal_matrix();
        n.validate("AᵀA").unwrap();
        let mut dense = vec![0.0f64; cols * cols];
        for r in 0..rows {
            for i in a.row_ptr[r]..a.row_ptr[r + 1] {
                for j in a.row_ptr[r]..a.row_ptr[r + 1] {
                    dense[a.col_idx[i] as usize * cols + a.col_idx[j] as usize] +=
                        a.values[i] as f64 * a.values[j] as f64;
                }
            }
        }
        for r in 0..cols {
            let mut row = vec![0.0f64; cols];
            for k in n.row_ptr[r]..n.row_ptr[r + 1] {
                row[n.col_idx[k] as usize] = n.values[k] as f64;
            }
            for c in 0..cols {
                prop_assert!((row[c] - dense[r * cols + c]).abs() < 1e-5);
            }
        }
    }
}

#[test]
fn builder_merges_duplicates_and_rejects_bad_columns() {
    let mut b = CsrBuilder::new(3);
    b.push_row(&[(2, 1.0), (0, 0.5), (2, 0.25)]).unwrap();
    assert!(matches!(
        b.push_row(&[(3, 1.0)]),
        Err(SolveError::ColumnOutOfRange {
            row: 1,
            col: 3,
            cols: 3
        })
    ));
    let a = b.finish();
    assert_eq!(
        (a.rows, a.col_idx.clone(), a.values.clone()),
        (1, vec![0, 2], vec![0.5, 1.25])
    );
    let s = CsrMatrix::vstack(&[&a, &a]).unwrap();
    assert_eq!((s.rows, s.row_ptr.clone()), (2, vec![0, 2, 4]));
    assert!(matches!(
        CsrMatrix::vstack(&[&a, &CsrMatrix::zeros(1, 4)]),
        Err(SolveError::DimensionMismatch {
            expected: 3,
            found: 4,
            ..
        })
    ));
}
