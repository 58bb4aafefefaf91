//! Texels and cube faces no pixel sees: filled by the pyramid term, kept
//! at the start value, or filled across seams by the seam term.

use super::*;

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

#[test]
fn the_prior_keeps_unseen_texels_near_zero_and_seen_ones_fitted() {
    let layout = tex(16, 16);
    let (a, b) = left_half(&layout, |_, _| 0.6);
    let far_right = |x: &[f32]| x[layout.index(0, 0, 15, 8)];
    let without = solve(&a, &b, &layout, None, &opts(0.1, None, 1e-6)).unwrap();
    let with = solve(
        &a,
        &b,
        &layout,
        None,
        &SolveOptions {
            eps_prior: 0.01,
            ..opts(0.1, None, 1e-6)
        },
    )
    .unwrap();
    assert!(with.converged, "{:?}", with.diagnostic);
    // Without the prior the pyramid spreads the seen value into the unseen
    // half; with it, texels far from any row fall toward zero (transparent).
    assert!(far_right(&without.x) > 0.5, "{}", far_right(&without.x));
    assert!(
        far_right(&with.x) < 0.5 * far_right(&without.x),
        "{}",
        far_right(&with.x)
    );
    // Seen texels still fit their rows to within a few percent.
    let seen = with.x[layout.index(0, 0, 3, 8)];
    assert!((seen - 0.6).abs() < 0.03, "{seen}");
    // A negative weight is refused by name.
    let bad = SolveOptions {
        eps_prior: -1.0,
        ..SolveOptions::default()
    };
    assert!(solve(&a, &b, &layout, None, &bad).is_err());
}
