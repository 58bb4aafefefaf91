//! Solver tests on small synthetic problems with known answers.

use proptest::prelude::*;

use super::*;

/// splitmix64: reproducible matrices from a proptest-shrinkable seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: usize) -> u32 {
        (self.next() % n as u64) as u32
    }
}

fn shape_from(pick: u8, size: u32) -> TextureShape {
    match pick % 3 {
        0 => TextureShape::Cube { size },
        1 => TextureShape::Tex2D {
            width: size,
            height: size * 2,
        },
        _ => TextureShape::Tex2D {
            width: size * 2 + 1,
            height: size,
        },
    }
}

/// Full-column-rank A: one dominant diagonal row per texel plus `extra`
/// random filter-like rows (8 taps), so AᵀA is well conditioned.
fn well_conditioned(n_t: usize, extra: usize, rng: &mut Rng) -> CsrMatrix {
    let mut b = CsrBuilder::new(n_t);
    for i in 0..n_t {
        let mut row = vec![(i as u32, 1.0 + rng.unit())];
        for _ in 0..3 {
            row.push((rng.below(n_t), 0.2 * (rng.unit() - 0.5)));
        }
        b.push_row(&row).unwrap();
    }
    for _ in 0..extra {
        let row: Vec<_> = (0..8).map(|_| (rng.below(n_t), rng.unit() / 4.0)).collect();
        b.push_row(&row).unwrap();
    }
    b.finish()
}

fn mul_f32(a: &CsrMatrix, x: &[f32]) -> Vec<f32> {
    let mut y = vec![0.0; a.rows];
    a.mul(x, &mut y);
    y
}

fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f32::max)
}

fn opts(eps_f: f32, form: Option<Form>, tolerance: f32) -> SolveOptions {
    SolveOptions {
        eps_f,
        force_form: form,
        tolerance,
        ..SolveOptions::default()
    }
}

fn tex(w: u32, h: u32) -> TextureLayout {
    TextureLayout::full_chain(TextureShape::Tex2D {
        width: w,
        height: h,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn recovers_x_true_in_both_forms(seed: u64, pick: u8, size in 1u32..6, extra in 0usize..40) {
        let layout = TextureLayout::full_chain(shape_from(pick, size));
        let mut rng = Rng(seed);
        let a = well_conditioned(layout.len(), extra, &mut rng);
        let x_true: Vec<f32> = (0..layout.len()).map(|_| rng.unit()).collect();
        let b = mul_f32(&a, &x_true);
        let mut answers = Vec::new();
        for form in [Form::A, Form::NormalMatrix] {
            let s = solve(&a, &b, &layout, None, &opts(0.0, Some(form), 1e-6)).unwrap();
            prop_assert!(s.converged, "{:?}: {:?}", form, s.diagnostic);
            prop_assert_eq!(s.form, form);
            prop_assert!(s.relative_residual <= 1e-6);
            prop_assert!(max_abs_diff(&s.x, &x_true) < 1e-4, "{:?} err {}", form, max_abs_diff(&s.x, &x_true));
            answers.push(s.x);
        }
        // With the pyramid term the forms must still agree with each other.
        let xa = solve(&a, &b, &layout, None, &opts(0.1, Some(Form::A), 1e-7)).unwrap();
        let xn = solve(&a, &b, &layout, None, &opts(0.1, Some(Form::NormalMatrix), 1e-7)).unwrap();
        prop_assert!(xa.converged && xn.converged);
        prop_assert!(max_abs_diff(&xa.x, &xn.x) < 1e-4);
    }

    #[test]
    fn warm_start_at_the_answer_takes_no_iterations(seed: u64, size in 1u32..6, extra in 0usize..20) {
        let layout = TextureLayout::full_chain(TextureShape::Cube { size });
        let mut rng = Rng(seed);
        let a = well_conditioned(layout.len(), extra, &mut rng);
        let x_true: Vec<f32> = (0..layout.len()).map(|_| rng.unit()).collect();
        let b = mul_f32(&a, &x_true);
        for form in [Form::A, Form::NormalMatrix] {
            let s = solve(&a, &b, &layout, Some(&x_true), &opts(0.0, Some(form), 1e-5)).unwrap();
            prop_assert!(s.converged);
            prop_assert_eq!(s.iterations, 0);
            prop_assert_eq!(&s.x, &x_true);
        }
    }

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

/// Identity rows on the left half of level 0 of a 16×16 texture.
fn left_half(layout: &TextureLayout, value: impl Fn(u32, u32) -> f32) -> (CsrMatrix, Vec<f32>) {
    let mut bld = CsrBuilder::new(layout.len());
    let mut b = Vec::new();
    for y in 0..16 {
        for x in 0..8 {
            bld.push_row(&[(layout.index(0, 0, x, y) as u32, 1.0)])
                .unwrap();
            b.push(value(x, y));
        }
    }
    (bld.finish(), b)
}

#[test]
fn unseen_texels_are_filled_finite_and_smooth() {
    let layout = tex(16, 16);
    // Constant data: the constant pyramid fits it exactly, everywhere.
    let (a, b) = left_half(&layout, |_, _| 0.6);
    for form in [Form::A, Form::NormalMatrix] {
        let s = solve(&a, &b, &layout, None, &opts(0.1, Some(form), 1e-6)).unwrap();
        assert!(s.converged, "{:?}", s.diagnostic);
        assert!(max_abs_diff(&s.x, &vec![0.6; layout.len()]) < 1e-3);
    }
    // A ramp: the unseen right half must be finite, bounded and smooth.
    let (a, b) = left_half(&layout, |x, _| x as f32 / 8.0);
    let s = solve(&a, &b, &layout, None, &opts(0.1, None, 1e-6)).unwrap();
    assert!(s.converged, "{:?}", s.diagnostic);
    assert!(s.x.iter().all(|v| v.is_finite()));
    for y in 0..16 {
        for x in 8..16 {
            let v = s.x[layout.index(0, 0, x, y)];
            assert!((-0.1..=1.0).contains(&v), "({x},{y}) = {v}");
            if x < 15 {
                let step = (s.x[layout.index(0, 0, x + 1, y)] - v).abs();
                assert!(step < 0.15, "jump {step} at ({x},{y})");
            }
        }
    }
}

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
fn huge_b_is_scale_invariant() {
    let layout = tex(8, 8);
    let mut rng = Rng(3);
    let a = well_conditioned(layout.len(), 50, &mut rng);
    let x_true: Vec<f32> = (0..layout.len()).map(|_| rng.unit()).collect();
    let b = mul_f32(&a, &x_true);
    let big: Vec<f32> = b.iter().map(|v| v * 1e6).collect();
    for form in [Form::A, Form::NormalMatrix] {
        let o = opts(0.1, Some(form), 1e-5);
        let small = solve(&a, &b, &layout, None, &o).unwrap();
        let large = solve(&a, &big, &layout, None, &o).unwrap();
        assert!(large.converged && large.relative_residual <= 1e-5);
        let scaled: Vec<f32> = large.x.iter().map(|v| v / 1e6).collect();
        assert!(max_abs_diff(&scaled, &small.x) < 1e-4);
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

#[test]
fn range_term_keeps_texels_in_range() {
    let layout = tex(4, 4);
    // Half-weight rows: the unconstrained fit of b = 0.8 is x = 1.6.
    let mut bld = CsrBuilder::new(layout.len());
    for i in 0..16 {
        bld.push_row(&[(i, 0.5)]).unwrap();
    }
    let a = bld.finish();
    let b = vec![0.8; 16];
    let base = opts(0.1, None, 1e-5);
    let free = solve(&a, &b, &layout, None, &base).unwrap();
    assert!(free.x[0] > 1.5);
    for (range_max, top) in [(Some(1.0), 1.0), (None, 0.8)] {
        let o = SolveOptions {
            eps_b: 1.0 / 32.0,
            range_max,
            ..base.clone()
        };
        let s = solve(&a, &b, &layout, None, &o).unwrap();
        assert!(s.converged, "{:?}", s.diagnostic);
        let hi = top * (1.0 + range::RANGE_DELTA as f32);
        assert!(s.x.iter().all(|&v| v > -0.01 && v < hi), "{:?}", s.x);
        assert!(s.x[0] > 0.9 * top, "barrier pushed too far: {}", s.x[0]);
    }
    // Inside the range a small ε_b barely moves the answer.
    let b = vec![0.3; 16];
    let o = SolveOptions {
        eps_b: 1.0 / 32.0,
        range_max: Some(1.0),
        ..base
    };
    let s = solve(&a, &b, &layout, None, &o).unwrap();
    assert!(s.converged && (s.x[0] - 0.6).abs() < 0.05, "{}", s.x[0]);
}

#[test]
fn channels_match_single_solves_and_thread_counts_do_not_matter() {
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: 16 });
    let mut rng = Rng(11);
    // Enough nonzeros for the parallel kernels to engage.
    let a = well_conditioned(layout.len(), 4000, &mut rng);
    let bs: Vec<Vec<f32>> = (0..3)
        .map(|_| (0..a.rows).map(|_| rng.unit()).collect())
        .collect();
    let refs: Vec<&[f32]> = bs.iter().map(|b| b.as_slice()).collect();
    let o = opts(0.1, None, 1e-6);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| solve_channels(&a, &refs, &layout, None, &o).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two);
    for (b, s) in refs.iter().zip(&one) {
        assert!(s.converged);
        assert_eq!(s, &solve(&a, b, &layout, None, &o).unwrap());
    }
    let err = solve_channels(&a, &refs, &layout, Some(&refs[..1]), &o).unwrap_err();
    assert!(matches!(err, SolveError::DimensionMismatch { .. }));
}

#[test]
fn k_switch_picks_the_form() {
    let layout = tex(4, 4); // 21 texels
    let mut rng = Rng(5);
    let tall = well_conditioned(layout.len(), 40, &mut rng); // 2·61 ≥ 4·21
    let short = well_conditioned(layout.len(), 0, &mut rng); // 2·21 < 4·21
    let o = SolveOptions::default();
    assert_eq!(
        Solver::new(&tall, &layout, &o).unwrap().form(),
        Form::NormalMatrix
    );
    assert_eq!(Solver::new(&short, &layout, &o).unwrap().form(), Form::A);
}

/// ‖Aᵀb − (AᵀA + λ_f PᵀP) x‖ / ‖Aᵀb‖ from the CSR reference matrices.
fn reference_residual(
    a: &CsrMatrix,
    b: &[f32],
    layout: &TextureLayout,
    eps_f: f64,
    x: &[f32],
) -> f64 {
    let lambda = eps_f * a.rows as f64 / a.cols as f64;
    let p = pyramid::pyramid_matrix(layout);
    let xd: Vec<f64> = x.iter().map(|&v| v as f64).collect();
    let bd: Vec<f64> = b.iter().map(|&v| v as f64).collect();
    let (mut ax, mut px) = (vec![0.0; a.rows], vec![0.0; p.rows]);
    a.mul(&xd, &mut ax);
    p.mul(&xd, &mut px);
    let r: Vec<f64> = ax.iter().zip(&bd).map(|(p, q)| q - p).collect();
    let (mut g, mut rhs, mut ptp) = (vec![0.0; a.cols], vec![0.0; a.cols], vec![0.0; a.cols]);
    a.mul_transpose(&r, &mut g);
    a.mul_transpose(&bd, &mut rhs);
    p.mul_transpose(&px, &mut ptp);
    let num: f64 = g
        .iter()
        .zip(&ptp)
        .map(|(g, t)| (g - lambda * t).powi(2))
        .sum();
    let den: f64 = rhs.iter().map(|v| v * v).sum();
    (num / den).sqrt()
}

#[test]
fn reported_residual_matches_the_reference_operator() {
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: 8 });
    let mut rng = Rng(21);
    let a = well_conditioned(layout.len(), 300, &mut rng);
    let b: Vec<f32> = (0..a.rows).map(|_| rng.unit()).collect();
    for form in [Form::A, Form::NormalMatrix] {
        let s = solve(&a, &b, &layout, None, &opts(0.1, Some(form), 1e-6)).unwrap();
        assert!(s.converged);
        let r = reference_residual(&a, &b, &layout, 0.1, &s.x);
        assert!(r < 3e-6, "{form:?}: reference residual {r}");
    }
}

#[test]
fn unseen_cube_faces_stay_at_their_start_value() {
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: 4 });
    let mut bld = CsrBuilder::new(layout.len());
    for y in 0..4 {
        for x in 0..4 {
            bld.push_row(&[(layout.index(0, 0, x, y) as u32, 1.0)])
                .unwrap();
        }
    }
    let a = bld.finish();
    let b = vec![0.5; 16];
    let o = opts(0.1, None, 1e-6);
    let cold = solve(&a, &b, &layout, None, &o).unwrap();
    let warm = solve(&a, &b, &layout, Some(&vec![0.25; layout.len()]), &o).unwrap();
    for (s, unseen) in [(cold, 0.0), (warm, 0.25)] {
        assert!(s.converged);
        let note = s.diagnostic.unwrap_or_default();
        assert!(note.contains("[1, 2, 3, 4, 5]"), "{note}");
        for i in 0..layout.len() {
            let (face, ..) = layout.coords(i);
            let want = if face == 0 { 0.5 } else { unseen };
            assert!((s.x[i] - want).abs() < 1e-4, "texel {i}: {}", s.x[i]);
        }
    }
}

#[test]
fn stacked_views_recover_the_texture() {
    let layout = tex(8, 8);
    let mut rng = Rng(9);
    // Each view alone sees only part of the texels; together they see all.
    let n = layout.len();
    let view = |lo: usize, hi: usize, rng: &mut Rng| {
        let mut bld = CsrBuilder::new(n);
        for i in lo..hi {
            bld.push_row(&[(i as u32, 0.8), (rng.below(n), 0.2)])
                .unwrap();
        }
        bld.finish()
    };
    let (v0, v1) = (view(0, n / 2 + 5, &mut rng), view(n / 2 - 5, n, &mut rng));
    let a = CsrMatrix::vstack(&[&v0, &v1]).unwrap();
    let x_true: Vec<f32> = (0..n).map(|_| rng.unit()).collect();
    let b = mul_f32(&a, &x_true);
    let s = solve(
        &a,
        &b,
        &layout,
        None,
        &opts(0.0, Some(Form::NormalMatrix), 1e-7),
    )
    .unwrap();
    assert!(s.converged && max_abs_diff(&s.x, &x_true) < 1e-3);
}

#[test]
fn range_solution_minimizes_the_objective() {
    let layout = tex(4, 4);
    let n = layout.len();
    let mut rng = Rng(17);
    let a = well_conditioned(n, 30, &mut rng);
    // Data asking for values outside [0, 1] so the barrier is active.
    let target: Vec<f32> = (0..n)
        .map(|i| if i % 3 == 0 { 1.4 } else { rng.unit() - 0.2 })
        .collect();
    let b = mul_f32(&a, &target);
    let (eps_f, eps_b) = (0.1f64, 1.0f64 / 32.0);
    let o = SolveOptions {
        eps_f: eps_f as f32,
        eps_b: eps_b as f32,
        range_max: Some(1.0),
        tolerance: 1e-6,
        ..SolveOptions::default()
    };
    let s = solve(&a, &b, &layout, None, &o).unwrap();
    assert!(s.converged, "{:?}", s.diagnostic);
    let ratio = a.rows as f64 / n as f64;
    let objective = |x: &[f32]| {
        let xd: Vec<f64> = x.iter().map(|&v| v as f64).collect();
        let mut ax = vec![0.0; a.rows];
        a.mul(&xd, &mut ax);
        let data: f64 = ax
            .iter()
            .zip(&b)
            .map(|(p, &q)| (p - q as f64).powi(2))
            .sum();
        let barrier: f64 = xd.iter().map(|&v| range::g(v)).sum();
        data + eps_f * ratio * pyramid::gamma(&layout, x)
            + eps_b * ratio * range::calibration() * barrier
    };
    let f0 = objective(&s.x);
    assert!(s.x.iter().all(|&v| v > -0.002 && v < 1.002));
    for k in 0..40 {
        let mut y = s.x.clone();
        let i = rng.below(n) as usize;
        y[i] += if k % 2 == 0 { 1e-3 } else { -1e-3 };
        assert!(objective(&y) >= f0 - 1e-9, "perturbing texel {i} lowered F");
    }
}

#[test]
fn hdr_range_scales_with_the_layer_max() {
    let layout = tex(4, 4);
    let mut bld = CsrBuilder::new(layout.len());
    for i in 0..16u32 {
        bld.push_row(&[(i, 0.5), ((i + 1) % 16, 0.25)]).unwrap();
    }
    let a = bld.finish();
    let b: Vec<f32> = (0..16)
        .map(|i| if i % 4 == 0 { 0.9 } else { 0.2 })
        .collect();
    let hdr: Vec<f32> = b.iter().map(|v| v * 1000.0).collect();
    let o = SolveOptions {
        eps_b: 1.0 / 32.0,
        tolerance: 1e-6,
        ..SolveOptions::default()
    };
    let ldr = solve(&a, &b, &layout, None, &o).unwrap();
    let big = solve(&a, &hdr, &layout, None, &o).unwrap();
    assert!(ldr.converged && big.converged, "{:?}", big.diagnostic);
    let scaled: Vec<f32> = big.x.iter().map(|v| v / 1000.0).collect();
    assert!(max_abs_diff(&scaled, &ldr.x) < 1e-4);
    assert!(
        big.x
            .iter()
            .all(|&v| v < 900.0 * (1.0 + range::RANGE_DELTA as f32))
    );
}

#[test]
fn seam_term_fills_unseen_faces_from_their_neighbours() {
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: 8 });
    let mut bld = CsrBuilder::new(layout.len());
    let mut b = Vec::new();
    for y in 0..8 {
        for x in 0..8 {
            bld.push_row(&[(layout.index(0, 0, x, y) as u32, 1.0)])
                .unwrap();
            b.push(0.5 + 0.02 * x as f32);
        }
    }
    let a = bld.finish();
    let o = SolveOptions {
        eps_seam: 0.1,
        ..opts(0.1, None, 1e-6)
    };
    for form in [Form::A, Form::NormalMatrix] {
        let s = solve(
            &a,
            &b,
            &layout,
            None,
            &SolveOptions {
                force_form: Some(form),
                ..o.clone()
            },
        )
        .unwrap();
        assert!(s.converged && s.diagnostic.is_none(), "{:?}", s.diagnostic);
        // Every face is filled near the seen face's values, none left at 0.
        for i in 0..layout.len() {
            assert!(
                (0.4..0.7).contains(&s.x[i]),
                "texel {:?} = {}",
                layout.coords(i),
                s.x[i]
            );
        }
    }
    // Constant data: the constant cube satisfies every term exactly.
    let flat = vec![0.5; b.len()];
    let s = solve(&a, &flat, &layout, None, &o).unwrap();
    assert!(max_abs_diff(&s.x, &vec![0.5; layout.len()]) < 1e-4);
}
