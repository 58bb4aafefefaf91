//! Empty, all-zero, non-finite, mismatched and singular inputs: named
//! errors or a finite answer with a diagnostic, never NaN or a hang.

use super::*;

#[test]
fn empty_a_returns_x0_or_zeros_with_a_diagnostic() {
    let layout = tex(4, 4);
    let a = CsrMatrix::zeros(0, layout.len());
    let s = solve(&a, &[], &layout, None, &SolveOptions::default()).unwrap();
    assert_eq!(s.x, vec![0.0; layout.len()]);
    assert!(s.diagnostic.is_some() && s.iterations == 0);
    let x0: Vec<f32> = (0..layout.len()).map(|i| i as f32).collect();
    let s = solve(&a, &[], &layout, Some(&x0), &SolveOptions::default()).unwrap();
    assert_eq!(s.x, x0);
    // Rows but no nonzeros (every weight truncated away).
    let a = CsrMatrix::zeros(5, layout.len());
    let s = solve(&a, &[1.0; 5], &layout, None, &SolveOptions::default()).unwrap();
    assert!(s.x.iter().all(|&v| v == 0.0) && s.diagnostic.is_some());
}

#[test]
fn all_zero_layer_gives_zero() {
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: 4 });
    let a = well_conditioned(layout.len(), 10, &mut Rng(7));
    let b = vec![0.0; a.rows];
    for eps_b in [0.0, 1.0 / 32.0] {
        let o = SolveOptions {
            eps_b,
            ..SolveOptions::default()
        };
        let s = solve(&a, &b, &layout, None, &o).unwrap();
        assert!(s.converged && s.x.iter().all(|&v| v == 0.0));
    }
}

#[test]
fn non_finite_inputs_are_named() {
    let layout = tex(4, 4);
    let mut a = well_conditioned(layout.len(), 0, &mut Rng(1));
    let mut b = vec![0.5; a.rows];
    b[3] = f32::NAN;
    let o = SolveOptions::default();
    assert_eq!(
        solve(&a, &b, &layout, None, &o).unwrap_err(),
        SolveError::NonFinite {
            what: "b",
            index: 3
        }
    );
    b[3] = 0.5;
    let mut x0 = vec![0.0; layout.len()];
    x0[5] = f32::NEG_INFINITY;
    assert_eq!(
        solve(&a, &b, &layout, Some(&x0), &o).unwrap_err(),
        SolveError::NonFinite {
            what: "x0",
            index: 5
        }
    );
    a.values[7] = f32::INFINITY;
    assert_eq!(
        solve(&a, &b, &layout, None, &o).unwrap_err(),
        SolveError::NonFinite {
            what: "A values",
            index: 7
        }
    );
}

#[test]
fn mismatched_dimensions_are_named() {
    let layout = tex(4, 4);
    let a = well_conditioned(layout.len(), 0, &mut Rng(1));
    let o = SolveOptions::default();
    let err = solve(&a, &[0.0; 3], &layout, None, &o).unwrap_err();
    assert!(matches!(
        err,
        SolveError::DimensionMismatch { found: 3, .. }
    ));
    let b = vec![0.0; a.rows];
    let err = solve(&a, &b, &layout, Some(&[0.0; 2]), &o).unwrap_err();
    assert!(matches!(
        err,
        SolveError::DimensionMismatch { found: 2, .. }
    ));
    let err = solve(&a, &b, &tex(8, 8), None, &o).unwrap_err();
    assert!(matches!(err, SolveError::DimensionMismatch { .. }));
    let bad = SolveOptions {
        tolerance: f32::NAN,
        ..o
    };
    assert!(matches!(
        solve(&a, &b, &layout, None, &bad).unwrap_err(),
        SolveError::InvalidOption {
            name: "tolerance",
            ..
        }
    ));
}

#[test]
fn singular_or_ill_conditioned_a_stops_without_nan() {
    let layout = tex(4, 4);
    let n = layout.len();
    // Two identical columns, several zero columns, no regularization.
    let mut bld = CsrBuilder::new(n);
    for r in 0..12 {
        bld.push_row(&[(0, 1.0), (1, 1.0), (2 + (r % 5) as u32, 0.5)])
            .unwrap();
    }
    let a = bld.finish();
    let b: Vec<f32> = (0..12).map(|r| r as f32 / 12.0).collect();
    for form in [Form::A, Form::NormalMatrix] {
        let o = SolveOptions {
            max_iterations: 50,
            ..opts(0.0, Some(form), 1e-6)
        };
        let s = solve(&a, &b, &layout, None, &o).unwrap();
        assert!(s.x.iter().all(|v| v.is_finite()) && s.relative_residual.is_finite());
        assert!(s.iterations <= 50);
        assert!(s.converged || s.diagnostic.is_some());
        assert_eq!(s.x[0], s.x[1]); // min-norm split of the duplicate pair
    }
    // Condition number ~1e14 and an unreachable tolerance: must stop.
    let mut bld = CsrBuilder::new(n);
    for i in 0..n {
        bld.push_row(&[(i as u32, 10f32.powi(-(i as i32 % 8)))])
            .unwrap();
    }
    bld.push_row(&[(0, 1.0), (n as u32 - 1, 1.0)]).unwrap();
    let a = bld.finish();
    let b = vec![1.0; a.rows];
    let o = SolveOptions {
        max_iterations: 5,
        ..opts(0.0, None, 0.0)
    };
    let s = solve(&a, &b, &layout, None, &o).unwrap();
    assert!(!s.converged && s.iterations <= 5);
    assert!(s.diagnostic.is_some_and(|d| d.contains("max_iterations")));
    assert!(s.x.iter().all(|v| v.is_finite()));
}
