//! The matrix builder against software devices whose filter is known.

use super::*;
use crate::solve::layout::{TextureLayout, TextureShape};
use glam::{Mat4, Vec2};

/// Samples level 0 of a 2D texture bilinearly (repeat wrap, texel centres
/// at (i + ½)/size), or with a `width`-texel box for the collision case.
/// Pixel (x, y) reads uv = (x·sx + ox, y·sy + oy).
struct SoftwareDevice {
    width: u32,
    height: u32,
    box_width: Option<i64>,
}

impl SoftwareDevice {
    fn sample(&self, layout: &TextureLayout, texels: &[[f32; 4]], uv: Vec2) -> [f32; 4] {
        let (w, h) = layout.level_size(0);
        let fx = uv.x * w as f32 - 0.5;
        let fy = uv.y * h as f32 - 0.5;
        let at = |x: i64, y: i64| {
            texels[layout.index(
                0,
                0,
                x.rem_euclid(w as i64) as u32,
                y.rem_euclid(h as i64) as u32,
            )]
        };
        let mut out = [0.0f32; 4];
        if let Some(n) = self.box_width {
            let (x0, y0) = (fx.floor() as i64, fy.floor() as i64);
            for dx in 0..n {
                let t = at(x0 + dx - n / 2, y0);
                for c in 0..4 {
                    out[c] += t[c] / n as f32;
                }
            }
            return out;
        }
        let (x0, y0) = (fx.floor(), fy.floor());
        let (ax, ay) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        for (dx, dy, wgt) in [
            (0, 0, (1.0 - ax) * (1.0 - ay)),
            (1, 0, ax * (1.0 - ay)),
            (0, 1, (1.0 - ax) * ay),
            (1, 1, ax * ay),
        ] {
            let t = at(x0 + dx, y0 + dy);
            for c in 0..4 {
                out[c] += wgt * t[c];
            }
        }
        out
    }
}

impl ProbeRenderer for SoftwareDevice {
    fn render(
        &mut self,
        g: &ProbeGeometry,
        layout: &TextureLayout,
        texels: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError> {
        let mut image = vec![[0.0; 4]; (self.width * self.height) as usize];
        for y in 0..self.height {
            for x in 0..self.width {
                // The object covers all but the left column.
                if x == 0 {
                    continue;
                }
                let uv = Vec2::new(x as f32 * 0.137 + 0.01, y as f32 * 0.093 + 0.02);
                let mut p = self.sample(layout, texels, uv);
                p[3] = 1.0;
                image[(y * self.width + x) as usize] = p;
            }
        }
        let _ = g;
        Ok(image)
    }
}

fn geometry(width: u32, height: u32) -> ProbeGeometry {
    ProbeGeometry {
        key: 1,
        positions: vec![],
        indices: vec![],
        lookup: Lookup::Uv(vec![]),
        view_proj: Mat4::IDENTITY,
        width,
        height,
    }
}

#[test]
fn matrix_reproduces_a_bilinear_device_exactly() {
    let shape = TextureShape::Tex2D {
        width: 16,
        height: 12,
    };
    let layout = TextureLayout::full_chain(shape);
    let mut device = SoftwareDevice {
        width: 24,
        height: 20,
        box_width: None,
    };
    let g = geometry(24, 20);
    let mut calls = 0;
    let m = build_matrix(&mut device, &g, &layout, shape, &mut |_, _| calls += 1).expect("matrix");
    assert_eq!(m.pixels.len(), 23 * 20, "rows = covered pixels");
    assert_eq!(m.probe_renders as usize, calls);
    assert!(m.a.nnz() <= 4 * m.pixels.len());
    let report = verify_matrix(&mut device, &g, &layout, &m, 7).expect("verify");
    assert!(report.psnr_db > 100.0, "{report:?}");
}

#[test]
fn a_filter_wider_than_the_spacing_is_reported_as_a_collision() {
    let shape = TextureShape::Tex2D {
        width: 16,
        height: 12,
    };
    let layout = TextureLayout::full_chain(shape);
    let mut device = SoftwareDevice {
        width: 24,
        height: 20,
        box_width: Some(10),
    };
    let result = build_matrix(
        &mut device,
        &geometry(24, 20),
        &layout,
        shape,
        &mut |_, _| {},
    );
    assert!(
        matches!(result, Err(ProbeError::Collision { .. })),
        "{:?}",
        result.err()
    );
}

#[test]
fn an_object_covering_no_pixel_gives_an_empty_matrix() {
    struct Nothing;
    impl ProbeRenderer for Nothing {
        fn render(
            &mut self,
            g: &ProbeGeometry,
            _: &TextureLayout,
            _: &[[f32; 4]],
        ) -> Result<Vec<[f32; 4]>, ProbeError> {
            Ok(vec![[0.0; 4]; (g.width * g.height) as usize])
        }
    }
    let shape = TextureShape::Cube { size: 8 };
    let layout = TextureLayout::full_chain(shape);
    let m = build_matrix(
        &mut Nothing,
        &geometry(8, 8),
        &layout,
        shape,
        &mut |_, _| {},
    )
    .expect("matrix");
    assert_eq!(m.a.rows, 0);
    assert!(m.pixels.is_empty());
}
