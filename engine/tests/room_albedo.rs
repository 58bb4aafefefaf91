//! The room passes draw procedural albedo in closed form: on the device,
//! `shaders/albedo.glsl` computes what `inference::scene::pattern_filter`
//! defines (box averages over each pixel's footprint, proven against brute
//! force there), for magnified, rotated and anisotropic, and minified
//! footprints; an unpatterned material still reads its texture.

mod common;

use common::*;
use engine::passes::room_albedo::SurfaceAlbedo;
use engine::probe::VulkanProbe;
use glam::{Mat4, Vec2, Vec3};
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::pattern_filter::footprint;
use inference::scene::{Pattern, Texture};
use inference::solve::layout::{TextureLayout, TextureShape};

const W: u32 = 64;
const H: u32 = 48;

/// A quad over the whole frame, given in clip space (identity view_proj),
/// whose uv is affine in the pixel: `uv = origin + x·ax + y·ay` at pixel
/// coordinates (x, y), so its screen derivatives are exactly `ax`, `ay`.
/// `key` names the geometry (the probe keeps an uploaded mesh per key).
fn affine_quad(key: u64, origin: Vec2, ax: Vec2, ay: Vec2) -> ProbeGeometry {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let uv = |(x, y): (f32, f32)| {
        origin + (x + 1.0) * 0.5 * W as f32 * ax + (y + 1.0) * 0.5 * H as f32 * ay
    };
    ProbeGeometry {
        key,
        positions: corners.iter().map(|&(x, y)| Vec3::new(x, y, 0.5)).collect(),
        indices: vec![0, 2, 1, 0, 3, 2],
        lookup: Lookup::Uv(corners.iter().map(|&c| uv(c)).collect()),
        view_proj: Mat4::IDENTITY,
        width: W,
        height: H,
    }
}

/// The device's albedo of `texture` over the quad against the closed form
/// at every pixel centre; returns the largest difference and the range of
/// the closed form's values.
fn compare(
    probe: &mut VulkanProbe,
    texture: &Texture,
    (key, origin): (u64, Vec2),
    ax: Vec2,
    ay: Vec2,
) -> (f32, f32) {
    let source = texture.pattern.expect("a baked pattern");
    let surface = SurfaceAlbedo::of(Vec3::ONE, Some(texture));
    assert_ne!(surface.variant, 0, "a pattern is drawn in closed form");
    let layout = TextureLayout::full_chain(TextureShape::Tex2D {
        width: 1,
        height: 1,
    });
    let got = probe
        .render_albedo(
            &affine_quad(key, origin, ax, ay),
            &layout,
            &[[1.0; 4]],
            surface,
        )
        .expect("albedo render");
    let w = footprint(ax, ay, 1.0 / texture.width as f32);
    let (mut worst, mut lo, mut hi) = (0.0f32, f32::MAX, f32::MIN);
    for y in 0..H {
        for x in 0..W {
            let uv = origin + (x as f32 + 0.5) * ax + (y as f32 + 0.5) * ay;
            let m = source.pattern.filtered_weight(uv, w, source.line_width);
            let want = source.colors[0].lerp(source.colors[1], m);
            let g = got[(y * W + x) as usize];
            let diff = (Vec3::new(g[0], g[1], g[2]) - want).abs().max_element();
            worst = worst.max(diff);
            (lo, hi) = (lo.min(m), hi.max(m));
        }
    }
    (worst, hi - lo)
}

#[test]
fn device_patterns_are_the_closed_form_box_averages() {
    let device = validated_device();
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    let colors = [Vec3::new(0.8, 0.78, 0.72), Vec3::new(0.08, 0.09, 0.12)];
    let checker = Texture::bake("checker", Pattern::Checker, colors, 0.0, 64);
    let bricks = Texture::bake("bricks", Pattern::Bricks, colors, 0.02, 512);
    let grid = Texture::bake("grid", Pattern::Grid, colors, 0.05, 256);
    let cases = [
        // Magnified across a check's edge: the baked texels' blur.
        (
            &checker,
            Vec2::new(0.45, 0.45),
            Vec2::new(0.002, 0.0),
            Vec2::new(0.0, 0.003),
        ),
        // Rotated and anisotropic over joints.
        (
            &bricks,
            Vec2::new(0.1, 0.2),
            Vec2::new(0.01, 0.004),
            Vec2::new(-0.002, 0.012),
        ),
        // About a pixel per line width.
        (
            &grid,
            Vec2::new(-0.3, 0.7),
            Vec2::new(0.03, 0.0),
            Vec2::new(0.0, 0.04),
        ),
    ];
    for (key, (texture, origin, ax, ay)) in (1..).zip(cases) {
        let (worst, range) = compare(&mut probe, texture, (key, origin), ax, ay);
        eprintln!(
            "{}: largest difference {worst:.2e}, weights span {range:.3}",
            texture.name
        );
        assert!(worst < 2e-3, "{}: {worst}", texture.name);
        assert!(
            range > 0.3,
            "{}: the view crosses edges ({range})",
            texture.name
        );
    }
    // Minified: many tiles per pixel average to the area share (½).
    let (worst, range) = compare(
        &mut probe,
        &checker,
        (10, Vec2::ZERO),
        Vec2::new(3.7, 0.0),
        Vec2::new(0.0, 5.3),
    );
    assert!(worst < 2e-3 && range < 0.05, "minified: {worst}, {range}");
    assert_no_validation_messages();
}

#[test]
fn an_unpatterned_material_reads_its_texture() {
    let device = validated_device();
    let mut probe = VulkanProbe::new(&device).expect("probe renderer");
    let layout = TextureLayout::full_chain(TextureShape::Tex2D {
        width: 2,
        height: 2,
    });
    let texels = vec![[0.25, 0.5, 0.75, 1.0]; layout.len()];
    let surface = SurfaceAlbedo::of(Vec3::new(1.0, 0.5, 2.0), None);
    assert_eq!(surface.variant, 0);
    let quad = affine_quad(1, Vec2::ZERO, Vec2::splat(0.01), Vec2::splat(0.01));
    let got = probe
        .render_albedo(&quad, &layout, &texels, surface)
        .expect("albedo render");
    for g in got {
        assert!(
            (g[0] - 0.25).abs() < 1e-6 && (g[1] - 0.25).abs() < 1e-6 && (g[2] - 1.5).abs() < 1e-6
        );
    }
    assert_no_validation_messages();
}
