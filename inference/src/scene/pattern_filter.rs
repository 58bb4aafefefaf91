//! The procedural patterns filtered in closed form: the share of
//! `colors[1]` seen through a pixel, weighted by a tent (a triangle kernel)
//! per tile axis. The room pass draws patterned albedo this way
//! (`shaders/albedo.glsl` is the same arithmetic, line for line) instead of
//! reading a MIP-mapped texture: one texture read fewer per pixel, and a
//! footprint per axis where a MIP level blurs both by the longer one.
//!
//! Each pattern is made of pulse trains (a pulse `[k, k + h)` in every
//! period `[k, k + 1)`). A tent-weighted average of a pulse train is the
//! second difference of its second antiderivative, which has a closed form.
//! Checker and grid are products of such trains along u and v, so their
//! averages under a separable tent are exact; bricks shift their vertical
//! joints by course and are exact within one course. The tent matches the
//! tracer's Gaussian film filter in variance and is closer to it in shape
//! than a box (an edge ramps as the tracer's does).

use glam::Vec2;

use super::texture::Pattern;

/// `∫₀ˣ ∫₀ᵗ pulse` for pulses of width `h` and period 1, any `x`.
fn pulse_integral2(x: f32, h: f32) -> f32 {
    let k = x.floor();
    let f = x - k;
    let partial = if f < h {
        0.5 * f * f
    } else {
        h * f - 0.5 * h * h
    };
    0.5 * h * k * (k - 1.0) + k * (h - 0.5 * h * h) + k * h * f + partial
}

/// The average of pulses `[k, k + h)`, `k` any integer, around `x` under a
/// tent of half-width `a > 0` (weight `(a − |s|)/a²`). Measured from the
/// period holding `x`, so large coordinates keep their precision; clamped
/// to [0, 1] against rounding in tents far narrower than a texel.
pub fn pulse_filtered(x: f32, a: f32, h: f32) -> f32 {
    let local = x - x.floor();
    let second = pulse_integral2(local + a, h) - 2.0 * pulse_integral2(local, h)
        + pulse_integral2(local - a, h);
    (second / (a * a)).clamp(0.0, 1.0)
}

/// The tent half-width per tile axis that matches, in variance, what the
/// tracer averages at a pixel: its film's Gaussian filter (σ = ½ pixel,
/// variance ¼ pixel², through the screen derivatives `dx`, `dy` in tiles)
/// and the baked texture it reads bilinearly (texels of `texel` tiles, each
/// a box average: variance `texel²/12 + texel²/6` = ¼ texel²). A tent of
/// half-width `a` has variance `a²/6`.
pub fn footprint(dx: Vec2, dy: Vec2, texel: f32) -> Vec2 {
    (1.5 * (dx * dx + dy * dy + Vec2::splat(texel * texel)))
        .max(Vec2::splat(1e-12))
        .sqrt()
}

impl Pattern {
    /// The share of `colors[1]` under a tent of half-width `w` (tiles per
    /// axis, > 0) centred on `uv`; `line_width` as the scene file gives it.
    pub fn filtered_weight(self, uv: Vec2, w: Vec2, line_width: f32) -> f32 {
        match self {
            Pattern::Checker => {
                // A check is half a tile: floor(2u) is even on [k, k + ½).
                let (eu, ev) = (
                    pulse_filtered(uv.x, w.x, 0.5),
                    pulse_filtered(uv.y, w.y, 0.5),
                );
                eu * (1.0 - ev) + ev * (1.0 - eu)
            }
            Pattern::Bricks => {
                // Courses ¼ tile tall with joints 2·line_width each side of
                // their border; bricks ½ tile wide with joints line_width
                // each side, odd courses shifted by ½ brick.
                let (wu, wv) = (line_width, 2.0 * line_width);
                let across = pulse_filtered(4.0 * uv.y + wv, 4.0 * w.y, 2.0 * wv);
                let even = pulse_filtered(2.0 * uv.y, 2.0 * w.y, 0.5);
                let joint =
                    |shift: f32| pulse_filtered(2.0 * uv.x + shift + wu, 2.0 * w.x, 2.0 * wu);
                let along = even * joint(0.0) + (1.0 - even) * joint(0.5);
                across + (1.0 - across) * along
            }
            Pattern::Grid => {
                // Lines line_width wide centred on the tile border.
                let h = 0.5 * line_width;
                let fu = pulse_filtered(uv.x + h, w.x, line_width);
                let fv = pulse_filtered(uv.y + h, w.y, line_width);
                1.0 - (1.0 - fu) * (1.0 - fv)
            }
        }
    }

    /// The shader's number for this pattern (`albedo.glsl`'s `PATTERN`;
    /// 0 is reserved for a texture read).
    pub fn shader_id(self) -> u32 {
        match self {
            Pattern::Checker => 1,
            Pattern::Bricks => 2,
            Pattern::Grid => 3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tent-weighted average by brute force: `n × n` point samples of
    /// the pattern's own definition over the tent's support.
    fn brute(p: Pattern, uv: Vec2, a: Vec2, line_width: f32, n: u32) -> f32 {
        let (mut sum, mut weights) = (0.0f64, 0.0f64);
        for j in 0..n {
            for i in 0..n {
                let s = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let t = (s - 0.5) * 2.0; // in [−1, 1]
                let weight = f64::from((1.0 - t.x.abs()) * (1.0 - t.y.abs()));
                let q = uv + t * a;
                let tile = q - q.floor();
                sum += weight * f64::from(u8::from(p.second_color(tile, line_width)));
                weights += weight;
            }
        }
        (sum / weights) as f32
    }

    #[test]
    fn pulse_average_is_the_tent_weighted_fraction() {
        // Inside a pulse, outside, centred on an edge, many periods.
        assert!((pulse_filtered(0.2, 0.1, 0.5) - 1.0).abs() < 1e-6);
        assert!(pulse_filtered(0.75, 0.1, 0.5).abs() < 1e-6);
        assert!((pulse_filtered(0.5, 0.2, 0.5) - 0.5).abs() < 1e-6);
        assert!((pulse_filtered(3.3, 10.0, 0.25) - 0.25).abs() < 1e-3);
        // A quarter of the tent past an edge: its tail holds 1/8 of the weight.
        assert!((pulse_filtered(0.45, 0.1, 0.5) - 0.875).abs() < 1e-5);
        // Far from the origin as near it; negative coordinates alike.
        let near = pulse_filtered(0.45, 0.01, 0.5);
        let far = pulse_filtered(1000.45, 0.01, 0.5);
        assert!((near - far).abs() < 1e-3, "{near} {far}");
        assert!((pulse_filtered(-0.55, 0.1, 0.5) - 0.875).abs() < 1e-5);
    }

    /// Every case's closed form within `tolerance` of brute force.
    fn check(p: Pattern, cases: &[(Vec2, Vec2)], line_width: f32, tolerance: f32) {
        for &(uv, w) in cases {
            let got = p.filtered_weight(uv, w, line_width);
            let want = brute(p, uv, w, line_width, 800);
            assert!(
                (got - want).abs() < tolerance,
                "{p:?} at {uv} over {w}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn closed_forms_match_brute_force_tent_averages() {
        let cases = [
            (Vec2::new(0.3, 0.7), Vec2::new(0.01, 0.02)),
            (Vec2::new(0.49, 0.26), Vec2::new(0.05, 0.3)),
            (Vec2::new(2.24, -1.49), Vec2::new(0.2, 0.013)),
            (Vec2::new(0.5, 0.5), Vec2::new(1.7, 1.3)),
            (Vec2::new(5.01, 3.99), Vec2::new(0.004, 0.004)),
        ];
        check(Pattern::Checker, &cases, 0.05, 4e-3);
        check(Pattern::Grid, &cases, 0.05, 4e-3);
        // Bricks are exact while the tent stays in one course (¼ tile) and
        // close when it spans several.
        let in_a_course = [
            (Vec2::new(0.3, 0.1), Vec2::new(0.02, 0.01)),
            (Vec2::new(0.26, 0.37), Vec2::new(0.3, 0.02)),
            (Vec2::new(1.74, 0.62), Vec2::new(0.05, 0.05)),
        ];
        check(Pattern::Bricks, &in_a_course, 0.02, 4e-3);
        let across_courses = [
            (Vec2::new(0.3, 0.25), Vec2::new(0.05, 0.1)),
            (Vec2::new(0.5, 0.5), Vec2::new(0.7, 0.9)),
        ];
        check(Pattern::Bricks, &across_courses, 0.02, 0.03);
    }

    #[test]
    fn wide_tents_give_the_pattern_mean_and_stay_finite() {
        // Over many tiles each pattern tends to its area share.
        let w = Vec2::splat(64.0);
        let uv = Vec2::new(0.37, 0.81);
        assert!((Pattern::Checker.filtered_weight(uv, w, 0.0) - 0.5).abs() < 0.01);
        let grid = 1.0 - (1.0 - 0.1f32) * (1.0 - 0.1);
        assert!((Pattern::Grid.filtered_weight(uv, w, 0.1) - grid).abs() < 0.01);
        assert!((Pattern::Bricks.filtered_weight(uv, w, 0.05) - 0.28).abs() < 0.01);
        // A tiny texel keeps the footprint positive at any magnification.
        let f = footprint(Vec2::ZERO, Vec2::ZERO, 0.0);
        assert!(f.min_element() > 0.0);
        for p in [Pattern::Checker, Pattern::Bricks, Pattern::Grid] {
            let v = p.filtered_weight(Vec2::new(1e4, -1e4), f, 0.05);
            assert!((0.0..=1.0).contains(&v), "{p:?}: {v}");
        }
    }
}
