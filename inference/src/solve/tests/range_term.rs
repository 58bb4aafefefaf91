//! The range term (ε_b): texels stay in [0, s], the answer minimizes the
//! full objective, and an HDR layer scales with its maximum.

use super::*;

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
