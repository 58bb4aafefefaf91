//! The tracer's primary rays line up with the rasteriser's pixels: the traced beauty and
//! the lavapipe frame of the same view agree best at zero shift, to a fraction of a pixel.
//! (Their shading differs; the checker, brick and silhouette edges they share do not.)

mod common;

use common::*;
use engine::renderer::{FrameMode, Renderer};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer};

const W: u32 = 160;
const H: u32 = 120;

/// Horizontal and vertical gradients of log luminance: edges, independent of exposure.
fn edges(lum: &[f32]) -> Vec<[f32; 2]> {
    let at = |x: u32, y: u32| (lum[(y * W + x) as usize].max(0.0) + 1e-3).ln();
    let mut out = vec![[0.0; 2]; (W * H) as usize];
    for y in 1..H - 1 {
        for x in 1..W - 1 {
            out[(y * W + x) as usize] = [at(x + 1, y) - at(x - 1, y), at(x, y + 1) - at(x, y - 1)];
        }
    }
    out
}

/// Normalised correlation of the edge maps with `b` shifted by `(dx, dy)` pixels.
fn correlation(a: &[[f32; 2]], b: &[[f32; 2]], dx: i32, dy: i32) -> f64 {
    let (mut ab, mut aa, mut bb) = (0.0f64, 0.0f64, 0.0f64);
    for y in 4..H as i32 - 4 {
        for x in 4..W as i32 - 4 {
            let p = a[(y * W as i32 + x) as usize];
            let q = b[((y + dy) * W as i32 + x + dx) as usize];
            for c in 0..2 {
                ab += f64::from(p[c]) * f64::from(q[c]);
                aa += f64::from(p[c]).powi(2);
                bb += f64::from(q[c]).powi(2);
            }
        }
    }
    ab / (aa * bb).sqrt().max(1e-12)
}

/// Vertex of the parabola through (−1, l), (0, c), (1, r).
fn peak(l: f64, c: f64, r: f64) -> f64 {
    let den = l - 2.0 * c + r;
    if den.abs() < 1e-12 {
        0.0
    } else {
        0.5 * (l - r) / den
    }
}

#[test]
fn traced_and_rasterised_pixels_line_up() {
    let scene = Scene::load("teapot").expect("scene");
    let eye = scene.orbit.sample_eye(30).expect("sample");

    let device = validated_device();
    let mut renderer = Renderer::new(&device, &scene, W, H).expect("renderer");
    renderer
        .frame(FrameMode::StaticEm, eye, scene.orbit.view(eye))
        .expect("frame");
    let raster: Vec<f32> = renderer
        .pixels()
        .expect("read back")
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect();

    let tracer = Tracer::new(&scene).expect("tracer");
    let settings = TraceSettings {
        width: W,
        height: H,
        spp: 4,
        ..TraceSettings::default()
    };
    let image = tracer.render(eye, &settings).expect("trace");
    let beauty = image.layer("beauty").expect("beauty");
    let traced: Vec<f32> = beauty
        .pixels
        .chunks(3)
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect();

    let (a, b) = (edges(&raster), edges(&traced));
    let c = |dx, dy| correlation(&a, &b, dx, dy);
    let centre = c(0, 0);
    assert!(centre > 0.5, "edge correlation {centre}: the images differ");
    for (dx, dy) in [
        (-1, 0),
        (1, 0),
        (0, -1),
        (0, 1),
        (-2, 0),
        (2, 0),
        (0, -2),
        (0, 2),
    ] {
        assert!(
            c(dx, dy) < centre,
            "shift ({dx}, {dy}) matches better than none"
        );
    }
    let px = peak(c(-1, 0), centre, c(1, 0));
    let py = peak(c(0, -1), centre, c(0, 1));
    eprintln!("edge correlation {centre:.3}, sub-pixel offset ({px:.3}, {py:.3})");
    assert!(px.abs() < 0.2 && py.abs() < 0.2, "offset ({px}, {py}) px");
    assert_no_validation_messages();
}
