//! The solve recovers known answers in both forms, warm starts cost
//! nothing at the answer, and the result does not depend on the scale of b,
//! the channel batching or the thread count.

use proptest::prelude::{ProptestConfig, prop_assert, prop_assert_eq, proptest};

use super::*;

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
