//! The screen rows a reflector covers, as horizontal bands of
//! [`BAND_ROWS`] rows, each with the span of columns its triangles reach:
//! the compositing pass draws one scissored screen triangle per band
//! instead of one over the reflector's bounding rectangle, so the device
//! rasterizes about one fragment per covered pixel (lavapipe counts, and
//! runs its rasterizer over, every pixel a draw's scissor lets through,
//! whatever the stencil test then rejects).
//!
//! Conservative by construction: every triangle adds its own screen
//! bounds, half a pixel wider, to the bands it reaches. Per frame that
//! is one projection per vertex and a min/max per triangle.

use super::target::intersect;
use ash::vk;
use glam::{Mat4, Vec2, Vec3};

/// Rows per band (lavapipe's 4×4 blocks).
pub const BAND_ROWS: u32 = 4;
/// Extra area, as a fraction, that merging two neighbouring bands may add.
const MERGE_SLACK: f32 = 0.03;

/// Scissor rectangles covering every pixel the triangles `indices` of
/// `positions` cover through `view_proj` on a `width × height` frame.
/// `pixels` is scratch (reused between frames). None when a vertex lies
/// at or behind the eye or an index is out of range (draw the bounding
/// rectangle instead).
pub fn screen_bands(
    view_proj: Mat4,
    positions: &[Vec3],
    indices: &[u32],
    size: (u32, u32),
    pixels: &mut Vec<Vec2>,
) -> Option<Vec<vk::Rect2D>> {
    project(view_proj, positions, size, pixels)?;
    bands_of(pixels, indices, size)
}

/// Every vertex's screen position in pixels (y down) into `pixels`; None
/// when one lies at or behind the eye (or is NaN), where no screen bound
/// holds.
pub fn project(
    view_proj: Mat4,
    positions: &[Vec3],
    (width, height): (u32, u32),
    pixels: &mut Vec<Vec2>,
) -> Option<()> {
    let size = Vec2::new(width as f32, height as f32);
    let [rx, ry, rw] = [view_proj.row(0), view_proj.row(1), view_proj.row(3)];
    pixels.clear();
    for p in positions {
        let p = p.extend(1.0);
        let w = rw.dot(p);
        // NaN fails this too.
        if w.is_nan() || w <= 1e-4 {
            return None;
        }
        let ndc = Vec2::new(rx.dot(p), ry.dot(p)) / w;
        pixels.push((ndc * 0.5 + 0.5) * size);
    }
    Some(())
}

/// [`screen_bands`] of triangles whose vertices [`project`] put at
/// `pixels`; None when an index is out of range.
pub fn bands_of(
    pixels: &[Vec2],
    indices: &[u32],
    (width, height): (u32, u32),
) -> Option<Vec<vk::Rect2D>> {
    let size = Vec2::new(width as f32, height as f32);
    let bands = height.div_ceil(BAND_ROWS) as usize;
    let mut spans = vec![(f32::INFINITY, f32::NEG_INFINITY); bands];
    // y in [0, height] after the clamp, so truncation is floor.
    let band = |y: f32| ((y.clamp(0.0, size.y) as u32 / BAND_ROWS) as usize).min(bands - 1);
    for t in indices.chunks_exact(3) {
        let a = *pixels.get(t[0] as usize)?;
        let b = *pixels.get(t[1] as usize)?;
        let c = *pixels.get(t[2] as usize)?;
        let (lo, hi) = (a.min(b).min(c) - 0.5, a.max(b).max(c) + 0.5);
        if !(lo.is_finite() && hi.is_finite()) {
            return None;
        }
        if hi.x < 0.0 || hi.y < 0.0 || lo.x > size.x || lo.y > size.y {
            continue;
        }
        for s in &mut spans[band(lo.y)..=band(hi.y)] {
            *s = (s.0.min(lo.x), s.1.max(hi.x));
        }
    }
    // Neighbouring bands merge into one rectangle while that adds under
    // MERGE_SLACK of their area: fewer draws, about the same fragments.
    let rows = BAND_ROWS as f32;
    // (x0, y0, x1, y1) and the area of the bands inside.
    let mut out: Vec<([f32; 4], f32)> = Vec::new();
    for (i, s) in spans.iter().enumerate().filter(|(_, s)| s.0 <= s.1) {
        let (y0, y1, area) = (i as f32 * rows, (i + 1) as f32 * rows, (s.1 - s.0) * rows);
        let merged = out.last().and_then(|&([x0, top, x1, bottom], sum)| {
            let (mx0, mx1) = (x0.min(s.0), x1.max(s.1));
            (bottom == y0 && (mx1 - mx0) * (y1 - top) <= (sum + area) * (1.0 + MERGE_SLACK))
                .then_some(([mx0, top, mx1, y1], sum + area))
        });
        match merged {
            Some(m) => *out.last_mut()? = m,
            None => out.push(([s.0, y0, s.1, y1], area)),
        }
    }
    let full = rect(0.0, 0.0, size.x, size.y);
    Some(
        out.into_iter()
            .filter_map(|([x0, y0, x1, y1], _)| {
                intersect(rect(x0.floor(), y0, x1.ceil(), y1), full)
            })
            .collect(),
    )
}

/// `bands` clipped to `within` (the pass's render area).
pub fn clipped(bands: &[vk::Rect2D], within: vk::Rect2D) -> Vec<vk::Rect2D> {
    bands.iter().filter_map(|b| intersect(*b, within)).collect()
}

fn rect(x0: f32, y0: f32, x1: f32, y1: f32) -> vk::Rect2D {
    let (x0, y0) = (x0.max(0.0) as i32, y0.max(0.0) as i32);
    let (x1, y1) = (x1.max(0.0) as i32, y1.max(0.0) as i32);
    vk::Rect2D {
        offset: vk::Offset2D { x: x0, y: y0 },
        extent: vk::Extent2D {
            width: x1.saturating_sub(x0) as u32,
            height: y1.saturating_sub(y0) as u32,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4Swizzles;

    fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
        glam::camera::rh::proj::vulkan::perspective(fov_y, aspect, near, far)
    }

    #[test]
    fn bands_cover_every_covered_pixel_and_little_more() {
        let (w, h) = (320u32, 240u32);
        let view_proj = perspective(0.8, w as f32 / h as f32, 0.1, 10.0)
            * Mat4::from_translation(Vec3::new(0.0, 0.0, -2.0));
        let n = 60;
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (
                    i as f32 / n as f32 * 2.0 - 1.0,
                    j as f32 / n as f32 * 2.0 - 1.0,
                );
                positions.push(Vec3::new(u, v, 0.0) * 0.6);
            }
        }
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let inside = |p: Vec3| p.length() < 0.55;
        for j in 0..n {
            for i in 0..n {
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                if q.iter().all(|&k| inside(positions[k as usize])) {
                    indices.extend([q[0], q[1], q[2], q[0], q[2], q[3]]);
                }
            }
        }
        let bands = screen_bands(view_proj, &positions, &indices, (w, h), &mut Vec::new())
            .expect("in front");
        let in_bands = |x: u32, y: u32| {
            bands.iter().any(|b| {
                let (bx, by) = (b.offset.x as u32, b.offset.y as u32);
                (bx..bx + b.extent.width).contains(&x) && (by..by + b.extent.height).contains(&y)
            })
        };
        // Rasterize by pixel centres (edge functions) and check each.
        let px = |k: u32| {
            let c = view_proj * positions[k as usize].extend(1.0);
            (c.xy() / c.w * 0.5 + 0.5) * glam::Vec2::new(w as f32, h as f32)
        };
        let mut covered = std::collections::HashSet::new();
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [px(t[0]), px(t[1]), px(t[2])];
            let lo = a.min(b).min(c).floor().max(glam::Vec2::ZERO);
            let hi = a.max(b).max(c).ceil();
            for y in lo.y as u32..(hi.y as u32).min(h) {
                for x in lo.x as u32..(hi.x as u32).min(w) {
                    let p = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let e = |p0: glam::Vec2, p1: glam::Vec2| (p1 - p0).perp_dot(p - p0);
                    let (e0, e1, e2) = (e(a, b), e(b, c), e(c, a));
                    let inside_t = (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0)
                        || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
                    if inside_t {
                        covered.insert((x, y));
                        assert!(in_bands(x, y), "pixel ({x}, {y}) outside every band");
                    }
                }
            }
        }
        let area: u32 = bands.iter().map(|b| b.extent.width * b.extent.height).sum();
        let covered = covered.len();
        assert!(covered > 5000, "{covered}");
        // The disc of ~76 pixels' radius in bands of 4 rows, some merged: under 1.1×.
        assert!((area as f64) < 1.1 * covered as f64, "{area} vs {covered}");
    }

    #[test]
    fn a_vertex_behind_the_eye_or_a_bad_index_falls_back() {
        let view_proj = perspective(0.8, 1.0, 0.1, 10.0);
        let full = rect(0.0, 0.0, 64.0, 64.0);
        let p = [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.1, 0.0, -1.0),
            Vec3::new(0.0, 0.1, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let bands =
            |p: &[Vec3], i: &[u32]| screen_bands(view_proj, p, i, (64, 64), &mut Vec::new());
        assert!(bands(&p, &[0, 1, 2]).is_none());
        assert!(bands(&p[..3], &[0, 1, 7]).is_none());
        let b = bands(&p[..3], &[0, 1, 2]).expect("bands");
        assert!(!b.is_empty() && b.iter().all(|r| r.offset.y % BAND_ROWS as i32 == 0));
        assert!(b.iter().all(|r| r.extent.height % BAND_ROWS == 0));
        // Clipped to a render area that misses them: none left.
        assert_eq!(clipped(&b, rect(60.0, 0.0, 64.0, 4.0)), []);
        // A triangle off screen adds no band.
        let off = [
            p[0] + Vec3::X * 5.0,
            p[1] + Vec3::X * 5.0,
            p[2] + Vec3::X * 5.0,
        ];
        assert_eq!(bands(&off, &[0, 1, 2]).expect("in front"), []);
        assert!(intersect(full, rect(70.0, 0.0, 80.0, 8.0)).is_none());
    }
}
