//! The bounds penalty (`eps_bound`): texels outside [0, hi] are pulled to
//! the bound by exactly the penalty's closed form, texels inside are left
//! as the least squares put them, and the fourth of four channels (α) is
//! the only one bounded above.

use super::*;

#[test]
fn bounds_pull_only_texels_outside_the_range() {
    let layout = tex(4, 4);
    // Half-weight rows on level 0: the free fit of b is x = 2b; coarser
    // levels are seen by no row (ε_f = 0) and stay 0.
    let mut bld = CsrBuilder::new(layout.len());
    for i in 0..16 {
        bld.push_row(&[(i, 0.5)]).unwrap();
    }
    let a = bld.finish();
    let red: Vec<f32> = (0..16)
        .map(|i| if i % 2 == 0 { -0.3 } else { 0.2 })
        .collect();
    let (green, blue, alpha) = (vec![0.8; 16], vec![0.2; 16], vec![0.8; 16]);
    let bs: Vec<&[f32]> = vec![&red, &green, &blue, &alpha];
    let free_opts = opts(0.0, None, 1e-7);
    let free = solve_channels(&a, &bs, &layout, None, &free_opts).unwrap();
    assert!((free[0].x[0] + 0.6).abs() < 1e-4 && (free[3].x[0] - 1.6).abs() < 1e-4);

    let w = 100.0f32;
    let o = SolveOptions {
        eps_bound: w,
        ..free_opts
    };
    let s = solve_channels(&a, &bs, &layout, None, &o).unwrap();
    // Minimizing (x/2 − b)² + w·(x − bound)² gives x = (b/2 + w·bound) / (1/4 + w).
    let pulled = |b: f32, bound: f32| (0.5 * b + w * bound) / (0.25 + w);
    for i in 0..16 {
        let want_red = if i % 2 == 0 { pulled(-0.3, 0.0) } else { 0.4 };
        assert!(
            (s[0].x[i] - want_red).abs() < 1e-4,
            "red {i}: {}",
            s[0].x[i]
        );
        assert!(
            (s[1].x[i] - 1.6).abs() < 1e-4,
            "colour is not bounded above"
        );
        assert!(
            (s[2].x[i] - 0.4).abs() < 1e-4,
            "inside the range: untouched"
        );
        assert!(
            (s[3].x[i] - pulled(0.8, 1.0)).abs() < 1e-4,
            "α {}",
            s[3].x[i]
        );
    }
    assert!(
        s.iter()
            .all(|c| c.converged && c.x[16..].iter().all(|&v| v == 0.0))
    );
}

#[test]
fn bounds_keep_a_random_fit_near_its_range() {
    let layout = tex(8, 8);
    let n = layout.len();
    let mut rng = Rng(5);
    let a = well_conditioned(n, 40, &mut rng);
    // Targets whose free fit leaves [0, 1] on many texels.
    let x_true: Vec<f32> = (0..n).map(|_| 3.0 * rng.unit() - 1.0).collect();
    let b = mul_f32(&a, &x_true);
    let bs: Vec<&[f32]> = vec![&b, &b, &b, &b];
    let base = opts(0.1, None, 1e-6);
    let free = solve_channels(&a, &bs, &layout, None, &base).unwrap();
    let outside = |x: &[f32], hi: f32| x.iter().filter(|&&v| v < -0.01 || v > hi + 0.01).count();
    assert!(
        outside(&free[3].x, 1.0) > n / 4,
        "the free fit must leave the range"
    );
    let o = SolveOptions {
        eps_bound: 1000.0,
        ..base
    };
    let s = solve_channels(&a, &bs, &layout, None, &o).unwrap();
    assert!(s.iter().all(|c| c.converged), "{:?}", s[3].diagnostic);
    assert_eq!(outside(&s[0].x, f32::INFINITY), 0, "colour ≥ 0");
    assert_eq!(outside(&s[3].x, 1.0), 0, "0 ≤ α ≤ 1");
}
