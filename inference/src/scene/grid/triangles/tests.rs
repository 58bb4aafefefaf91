use super::*;

/// 9 lines 1° apart on the orbit; rings at 10° and 20° keep every 4th
/// (and the last): lines 0, 4, 8.
fn sparse() -> ViewGrid {
    ViewGrid {
        azimuths_deg: (0..9).map(|k| k as f32).collect(),
        elevations_deg: vec![0.0, 10.0, 20.0],
        ring_line_every: 4,
        ..Default::default()
    }
}

fn tensor() -> ViewGrid {
    ViewGrid {
        azimuths_deg: vec![0.0, 4.0, 10.0],
        elevations_deg: vec![0.0, 15.0, 30.0],
        ring_line_every: 1,
        ..Default::default()
    }
}

fn triangles(g: &ViewGrid, az: f32, el: f32) -> SampleBlend {
    g.blend_by(az, el, 1, true, ViewBlend::Triangles)
}

/// The weights as a dense vector over the grid's samples.
fn dense(g: &ViewGrid, b: &SampleBlend) -> Vec<f32> {
    let mut w = vec![0.0; g.len() as usize];
    for &(k, x) in &b.samples {
        w[k as usize] += x;
    }
    w
}

#[test]
fn between_rings_three_samples_reproduce_the_view() {
    for g in [sparse(), tensor()] {
        let (a_max, e_max) = (
            *g.azimuths_deg.last().unwrap(),
            *g.elevations_deg.last().unwrap(),
        );
        for ia in 0..=40 {
            for ie in 1..40 {
                let (az, el) = (a_max * ia as f32 / 40.0, e_max * ie as f32 / 40.0);
                let b = triangles(&g, az, el);
                assert!(b.samples.len() <= 3, "{az} {el}: {b:?}");
                let sum: f32 = b.samples.iter().map(|s| s.1).sum();
                assert!((sum - 1.0).abs() < 1e-5, "{b:?}");
                // Linear precision: the weighted corners are the view.
                let (mut x, mut y) = (0.0, 0.0);
                for &(k, w) in &b.samples {
                    assert!(w > 0.0, "{b:?}");
                    let (ka, ke) = g.angles(k);
                    x += w * ka;
                    y += w * ke;
                }
                assert!(
                    (x - az).abs() < 1e-3 && (y - el).abs() < 1e-3,
                    "{az} {el}: {b:?}"
                );
            }
        }
    }
}

#[test]
fn weights_move_continuously_and_meet_the_rings_own_blend() {
    let g = sparse();
    let step = 20.0 / 20_000.0;
    for ia in 0..160 {
        let az = 8.0 * ia as f32 / 160.0;
        let mut last = dense(&g, &g.blend(az, 0.0, 1, true));
        for ie in 1..=20_000 {
            let el = 20.0 * ie as f32 / 20_000.0;
            let now = dense(&g, &triangles(&g, az, el));
            let jump: f32 = now.iter().zip(&last).map(|(a, b)| (a - b).abs()).sum();
            // Piecewise linear: a step of 1e-3° moves the weights by
            // ~1e-3 at most in these triangles; a seam would move them
            // by a good fraction of 1.
            assert!(jump < 10.0 * step, "{az} {el}: {jump}");
            last = now;
        }
        // On the top ring: its own 1D blend.
        assert_eq!(last, dense(&g, &g.blend(az, 20.0, 1, true)), "{az}");
    }
}

#[test]
fn on_rings_beyond_the_grid_and_bad_input_fall_back_to_the_cell() {
    let g = sparse();
    for (az, el) in [
        (3.0, 0.0),
        (7.0, 10.0),
        (5.5, 20.0),
        (-4.0, 5.0),
        (3.0, 45.0),
        (3.0, -5.0),
    ] {
        assert_eq!(triangles(&g, az, el), g.blend(az, el, 1, true), "{az} {el}");
    }
    for (az, el) in [
        (f32::NAN, 5.0),
        (3.0, f32::NAN),
        (f32::INFINITY, f32::NEG_INFINITY),
    ] {
        assert!(triangles(&g, az, el).indices().all(|k| k < g.len()));
    }
    // Lines in use that the sparse rings do not hold: no triangles there.
    let subset = sparse().with_azimuths_used(Some(&[1, 2, 3]));
    for (az, el) in [(2.5, 5.0), (2.5, 15.0), (7.0, 12.0)] {
        let b = triangles(&subset, az, el);
        assert_eq!(b, subset.blend(az, el, 1, true), "{az} {el}");
    }
    // Nearest alone and the bilinear rule are the cell's as before.
    assert_eq!(
        g.blend_by(3.3, 5.0, 1, false, ViewBlend::Triangles),
        g.blend(3.3, 5.0, 1, false)
    );
    assert_eq!(
        g.blend_by(3.3, 5.0, 1, true, ViewBlend::Bilinear),
        g.blend(3.3, 5.0, 1, true)
    );
    // The bilinear cell there has four corners; the triangle three.
    assert_eq!(g.blend(3.3, 5.0, 1, true).samples.len(), 4);
    assert_eq!(triangles(&g, 3.3, 5.0).samples.len(), 3);
}

#[test]
fn the_ribbon_covers_its_strip_and_prefers_short_diagonals() {
    let lower: Vec<f32> = (0..=8).map(|k| k as f32).collect();
    let upper = [0.0, 4.0, 8.0];
    for ix in 0..=80 {
        for it in 0..=10 {
            let (x, t) = (ix as f32 / 10.0, it as f32 / 10.0);
            assert!(ribbon_weights(&lower, &upper, x, t).is_some(), "{x} {t}");
        }
    }
    assert!(ribbon_weights(&lower, &upper, 8.5, 0.5).is_none());
    // Just under the upper line 4: a triangle with that corner, not one
    // reaching across to the upper line 0 or 8.
    let w = ribbon_weights(&lower, &upper, 4.0, 0.99).expect("inside");
    assert!(w.iter().any(|&(c, x)| c == (true, 1) && x > 0.9), "{w:?}");
}

proptest::proptest! {
    /// Any grid (lines unevenly spaced, sparse upper rings, subsets in
    /// use), any view: no panic, samples in range, weights positive and
    /// summing to 1 (three from a triangle, up to four where the cell's
    /// blend stands in).
    #[test]
    fn any_grid_and_view_give_a_valid_blend(
        steps in proptest::collection::vec(0.1f32..5.0, 1..12),
        rings in proptest::collection::vec(1.0f32..15.0, 0..4),
        every in 0u32..5,
        used in proptest::option::of(proptest::collection::vec(1u32..14, 0..6)),
        az in -30.0f32..60.0,
        el in -10.0f32..70.0,
        spacing in 1u32..3,
    ) {
        let azimuths_deg = std::iter::once(0.0)
            .chain(steps.iter().scan(0.0, |a, s| { *a += s; Some(*a) }))
            .collect();
        let elevations_deg = std::iter::once(0.0)
            .chain(rings.iter().scan(0.0, |e, s| { *e += s; Some(*e) }))
            .collect();
        let g = ViewGrid { azimuths_deg, elevations_deg, ring_line_every: every, ..Default::default() }
            .with_azimuths_used(used.as_deref());
        let b = g.blend_by(az, el, spacing, true, ViewBlend::Triangles);
        proptest::prop_assert!(b.indices().all(|k| k < g.len()), "{:?}", b);
        proptest::prop_assert!(b.samples.iter().all(|s| s.1 > 0.0));
        let sum: f32 = b.samples.iter().map(|s| s.1).sum();
        proptest::prop_assert!((sum - 1.0).abs() < 1e-4, "{:?}", b);
        proptest::prop_assert!(b.samples.len() <= 4);
    }
}
