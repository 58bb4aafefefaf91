//! Numerical extremes of `infer_layer`, on a software device that shows
//! pixel (x, y) the average of two neighbouring texels of level 0.

use super::*;
use crate::probe::{Lookup, ProbeError, ProbeGeometry, ProbeRenderer};
use crate::solve::SolveOptions;
use crate::solve::layout::{TextureLayout, TextureShape};

struct Device {
    covered: bool,
}

const W: u32 = 12;
const H: u32 = 8;
const SHAPE: TextureShape = TextureShape::Tex2D {
    width: 16,
    height: 8,
};

impl ProbeRenderer for Device {
    fn render(
        &mut self,
        _: &ProbeGeometry,
        l: &TextureLayout,
        t: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError> {
        let mut image = vec![[0.0; 4]; (W * H) as usize];
        if !self.covered {
            return Ok(image);
        }
        for y in 0..H {
            for x in 0..W {
                let a = t[l.index(0, 0, x, y)];
                let b = t[l.index(0, 0, x + 1, y)];
                image[(y * W + x) as usize] = [
                    0.5 * (a[0] + b[0]),
                    0.5 * (a[1] + b[1]),
                    0.5 * (a[2] + b[2]),
                    1.0,
                ];
            }
        }
        Ok(image)
    }
}

fn geometry() -> ProbeGeometry {
    ProbeGeometry {
        key: 0,
        positions: vec![],
        indices: vec![],
        lookup: Lookup::Uv(vec![]),
        view_proj: glam::Mat4::IDENTITY,
        width: W,
        height: H,
    }
}

fn run_with(
    pixels: &[[f32; 4]],
    covered: bool,
    options: &SolveOptions,
) -> Result<LayerResult, InferError> {
    let target = Target {
        name: "test.layer",
        pixels,
        channels: 3,
    };
    infer_layer(
        &mut Device { covered },
        &geometry(),
        SHAPE,
        &target,
        None,
        options,
        &mut |_, _| {},
    )
}

fn run(pixels: &[[f32; 4]], covered: bool) -> Result<LayerResult, InferError> {
    run_with(pixels, covered, &SolveOptions::default())
}

fn gradient(scale: f32) -> Vec<[f32; 4]> {
    (0..W * H)
        .map(|i| {
            let v = scale * ((i % W) as f32 + 1.0) / W as f32;
            [v, 0.5 * v, 0.25 * v, 1.0]
        })
        .collect()
}

#[test]
fn fits_a_reachable_target_and_beats_forward_mapping() {
    // Without the pyramid term a reachable target is fitted to the CG
    // tolerance; with it (the default) the fit trades a little accuracy
    // for smoothness yet still beats forward mapping.
    let exact = SolveOptions {
        eps_f: 0.0,
        ..SolveOptions::default()
    };
    let r = run_with(&gradient(1.0), true, &exact).expect("infer");
    assert!(
        r.psnr_least_squares_db > 70.0,
        "{}",
        r.psnr_least_squares_db
    );
    let r = run(&gradient(1.0), true).expect("infer");
    assert!(
        r.psnr_least_squares_db >= r.psnr_forward_db,
        "{} vs {}",
        r.psnr_least_squares_db,
        r.psnr_forward_db
    );
    assert!(
        r.map.iter().flatten().all(|v| v.is_finite()),
        "unseen texels stay finite"
    );
}

#[test]
fn an_all_zero_layer_gives_a_zero_map() {
    let r = run(&vec![[0.0, 0.0, 0.0, 1.0]; (W * H) as usize], true).expect("infer");
    assert!(r.map.iter().flatten().all(|&v| v == 0.0));
}

#[test]
fn values_up_to_1e6_solve_as_well_as_unit_values() {
    let unit = run(&gradient(1.0), true).expect("unit");
    let huge = run(&gradient(1e6), true).expect("1e6");
    assert!(huge.map.iter().flatten().all(|v| v.is_finite()));
    assert!(
        (huge.psnr_least_squares_db - unit.psnr_least_squares_db).abs() < 3.0
            || huge.psnr_least_squares_db > 60.0
    );
}

#[test]
fn nan_in_the_target_names_the_layer_and_pixel() {
    let mut pixels = gradient(1.0);
    pixels[17][1] = f32::NAN;
    let err = run(&pixels, true).err().expect("error").to_string();
    assert!(
        err.contains("test.layer") && err.contains("pixel 17") && err.contains("channel 1"),
        "{err}"
    );
}

#[test]
fn an_object_covering_no_pixel_stays_finite() {
    let r = run(&gradient(1.0), false).expect("infer");
    assert_eq!(r.rows, 0);
    assert!(r.map.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn a_four_channel_layer_is_scored_on_the_alpha_it_will_composite_with() {
    // The device writes coverage (1) into alpha; the layer's own alpha is
    // 0.3 here. Scored on the rendered alpha, an exact fit scores high; the
    // coverage alpha would have cost it the whole alpha channel.
    let pixels: Vec<[f32; 4]> = gradient(1.0)
        .into_iter()
        .map(|[r, g, b, _]| [0.3 * r, 0.3 * g, 0.3 * b, 0.3])
        .collect();
    let target = Target {
        name: "test.local",
        pixels: &pixels,
        channels: 4,
    };
    let exact = SolveOptions {
        eps_f: 0.0,
        ..SolveOptions::default()
    };
    let r = infer_layer(
        &mut Device { covered: true },
        &geometry(),
        SHAPE,
        &target,
        None,
        &exact,
        &mut |_, _| {},
    )
    .expect("infer");
    assert!(
        r.psnr_least_squares_db > 60.0,
        "{}",
        r.psnr_least_squares_db
    );
    let alpha = r
        .pixels
        .iter()
        .map(|&p| r.rendered_least_squares[p as usize][3]);
    assert!(
        alpha.clone().all(|a| (a - 0.3).abs() < 1e-3),
        "{:?}",
        alpha.collect::<Vec<_>>()
    );
}

/// The exact fit (no smoothness) of `own` with `neighbour`'s rows stacked
/// beside it, scaled by `w` and per pixel by `pixel_weights`.
fn fit_beside(
    own: &[[f32; 4]],
    neighbour: &[[f32; 4]],
    w: f32,
    pixel_weights: Option<&[f32]>,
) -> LayerResult {
    try_fit_beside(own, neighbour, w, pixel_weights).expect("infer")
}

fn try_fit_beside(
    own: &[[f32; 4]],
    neighbour: &[[f32; 4]],
    w: f32,
    pixel_weights: Option<&[f32]>,
) -> Result<LayerResult, InferError> {
    let exact = SolveOptions {
        eps_f: 0.0,
        ..SolveOptions::default()
    };
    let target = Target {
        name: "test.layer",
        pixels: own,
        channels: 3,
    };
    let g = geometry();
    let views = Views {
        own: View {
            id: 0,
            geometry: &g,
            target,
            weight: 1.0,
            pixel_weights: None,
        },
        neighbours: &[View {
            id: 1,
            geometry: &g,
            target: Target {
                pixels: neighbour,
                ..target
            },
            weight: w,
            pixel_weights,
        }],
        cache: &mut MatrixCache::new(2),
    };
    infer_layer_with(
        &mut Device { covered: true },
        views,
        SHAPE,
        None,
        &exact,
        &mut |_, _| {},
    )
}

/// Asserts every pixel of `r` renders `scale(x)` × its `own` value, x the
/// pixel's column (pixels whose scale is None are not checked).
fn assert_renders_scaled(r: &LayerResult, own: &[[f32; 4]], scale: impl Fn(u32) -> Option<f32>) {
    for (&p, rendered) in r.pixels.iter().zip(&r.rendered_least_squares) {
        let Some(s) = scale(p % W) else { continue };
        let want = s * own[p as usize][0];
        assert!(
            (rendered[0] - want).abs() <= 1e-3 * want.max(1.0),
            "pixel {p} renders {} for {want} ({s} b)",
            rendered[0]
        );
    }
}

#[test]
fn a_neighbouring_view_pulls_the_fit_by_its_weight() {
    // Both views see the same texels; the neighbour's target is twice the
    // sample's. Rows scaled by w minimise |Ax − b|² + w²|Ax − 2b|², so the
    // render is (1 + 2w²) / (1 + w²) × b: 1.2 b at w = ½, 1.5 b at w = 1.
    let own = gradient(1.0);
    let twice = gradient(2.0);
    for (w, expected) in [(0.5f32, 1.2f32), (1.0, 1.5)] {
        let r = fit_beside(&own, &twice, w, None);
        assert_renders_scaled(&r, &own, |_| Some(expected));
    }
}

#[test]
fn pixel_weights_scale_their_own_rows_only() {
    // As above at w = 1, but the neighbour's rows weighted per pixel: 0 on
    // the left half (the own view alone decides: b), 1 on the right half
    // (1.5 b). Weight 0 is what a pixel without confidence gets.
    let own = gradient(1.0);
    let twice = gradient(2.0);
    let weights: Vec<f32> = (0..W * H)
        .map(|p| if p % W < W / 2 { 0.0 } else { 1.0 })
        .collect();
    let r = fit_beside(&own, &twice, 1.0, Some(&weights));
    // Pixels next to the halves' border share a texel with the other half.
    assert_renders_scaled(&r, &own, |x| match x {
        _ if x + 1 < W / 2 => Some(1.0),
        _ if x > W / 2 => Some(1.5),
        _ => None,
    });
}

#[test]
fn pixel_weights_of_the_wrong_count_or_not_finite_name_the_layer() {
    let own = gradient(1.0);
    let short = vec![1.0f32; (W * H - 1) as usize];
    let mut nan = vec![1.0f32; (W * H) as usize];
    nan[5] = f32::NAN;
    let negative: Vec<f32> = (0..W * H)
        .map(|p| if p == 7 { -1.0 } else { 1.0 })
        .collect();
    for (weights, expect) in [
        (&short, "95 values"),
        (&nan, "at pixel 5"),
        (&negative, "at pixel 7"),
    ] {
        let Err(err) = try_fit_beside(&own, &own, 1.0, Some(weights)) else {
            panic!("weights {expect}: accepted");
        };
        let text = err.to_string();
        assert!(
            text.contains("test.layer") && text.contains(expect),
            "{text}"
        );
    }
}

/// Counts the renders it passes on to the software device.
struct Counting {
    device: Device,
    renders: usize,
}

impl ProbeRenderer for Counting {
    fn render(
        &mut self,
        g: &ProbeGeometry,
        l: &TextureLayout,
        t: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError> {
        self.renders += 1;
        self.device.render(g, l, t)
    }
}

#[test]
fn the_next_samples_solve_probes_no_view_already_kept() {
    // Sample 0 stacks view 1; sample 1 stacks view 0: its two matrices are
    // both kept, so it renders only its checks and pictures.
    let own = gradient(1.0);
    let g = geometry();
    let mut cache = MatrixCache::new(4);
    let mut device = Counting {
        device: Device { covered: true },
        renders: 0,
    };
    let mut renders = Vec::new();
    for (own_id, neighbour_id) in [(0, 1), (1, 0)] {
        let view = |id| View {
            id,
            geometry: &g,
            target: Target {
                name: "test.layer",
                pixels: &own,
                channels: 3,
            },
            weight: 0.5,
            pixel_weights: None,
        };
        let views = Views {
            own: view(own_id),
            neighbours: &[view(neighbour_id)],
            cache: &mut cache,
        };
        let before = device.renders;
        infer_layer_with(
            &mut device,
            views,
            SHAPE,
            None,
            &SolveOptions::default(),
            &mut |_, _| {},
        )
        .expect("infer");
        renders.push(device.renders - before);
    }
    assert_eq!(cache.hits(), 2);
    let probes_per_matrix = (renders[0] - renders[1]) / 2;
    assert!(
        probes_per_matrix > 0 && renders[0] == renders[1] + 2 * probes_per_matrix,
        "{renders:?}"
    );
}
