//! Procedural textures, baked once at load into linear RGBA f32 texels. The GPU upload and
//! the CPU tracer both use these texels, so there is one source of truth.

use glam::{Vec2, Vec3, Vec4};

/// Linear RGBA, row-major (row 0 at v = 0), repeat wrap; one texture tile = one repeat.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 4]>,
    /// The pattern it was baked from, when it was: the room pass draws
    /// patterns in closed form instead of reading the texels.
    pub pattern: Option<PatternSource>,
}

/// What a procedural texture was baked from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatternSource {
    pub pattern: Pattern,
    /// `colors[0]`, `colors[1]` (linear).
    pub colors: [Vec3; 2],
    /// Joint or line width, in tiles.
    pub line_width: f32,
}

/// A pattern over one tile, in tile coordinates [0, 1)².
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pattern {
    /// 2×2 checks per tile: `colors[0]`, `colors[1]`.
    Checker,
    /// Four courses of two 2:1 bricks per tile, alternate courses offset by half a brick:
    /// `colors[0]` bricks, `colors[1]` mortar joints of width `line_width`.
    Bricks,
    /// One cell per tile: `colors[0]` background, `colors[1]` lines of width `line_width`
    /// along the tile border.
    Grid,
}

/// Sub-samples per texel edge: a 4×4 box filter keeps pattern edges anti-aliased.
const SUPERSAMPLE: u32 = 4;

impl Pattern {
    /// Returns the weight of `colors[1]` at tile point `p` (0 or 1).
    pub(super) fn second_color(self, p: Vec2, line_width: f32) -> bool {
        let (u, v) = (p.x, p.y);
        match self {
            Pattern::Checker => ((2.0 * u).floor() + (2.0 * v).floor()) as i32 % 2 == 1,
            Pattern::Bricks => {
                // Bricks are ½ tile wide and ¼ tile tall, odd courses shifted by ½ brick.
                // In brick units a joint `line_width` wide (tile units) reaches
                // `line_width` into each brick horizontally and `2 × line_width` vertically.
                let course = (4.0 * v).floor();
                let shift = if course as i32 % 2 == 1 { 0.25 } else { 0.0 };
                let bu = (2.0 * (u + shift)).fract();
                let bv = (4.0 * v).fract();
                let (wu, wv) = (line_width, 2.0 * line_width);
                bu < wu || bu > 1.0 - wu || bv < wv || bv > 1.0 - wv
            }
            Pattern::Grid => {
                let h = 0.5 * line_width;
                u < h || u > 1.0 - h || v < h || v > 1.0 - h
            }
        }
    }
}

impl Texture {
    /// Bakes `pattern` into a `resolution²` tile.
    pub fn bake(
        name: &str,
        pattern: Pattern,
        colors: [Vec3; 2],
        line_width: f32,
        resolution: u32,
    ) -> Texture {
        let n = resolution as usize;
        let mut texels = Vec::with_capacity(n * n);
        let inv = 1.0 / (resolution * SUPERSAMPLE) as f32;
        let weight = 1.0 / (SUPERSAMPLE * SUPERSAMPLE) as f32;
        for y in 0..resolution {
            for x in 0..resolution {
                let mut c = Vec3::ZERO;
                for sy in 0..SUPERSAMPLE {
                    for sx in 0..SUPERSAMPLE {
                        let p = Vec2::new(
                            ((x * SUPERSAMPLE + sx) as f32 + 0.5) * inv,
                            ((y * SUPERSAMPLE + sy) as f32 + 0.5) * inv,
                        );
                        c += colors[pattern.second_color(p, line_width) as usize];
                    }
                }
                texels.push((c * weight).extend(1.0).to_array());
            }
        }
        Texture {
            name: name.to_owned(),
            width: resolution,
            height: resolution,
            texels,
            pattern: Some(PatternSource {
                pattern,
                colors,
                line_width,
            }),
        }
    }

    /// Texel at integer coordinates, wrapped; zero for an empty or inconsistent texture.
    pub fn texel(&self, x: i64, y: i64) -> Vec4 {
        let (w, h) = (self.width as i64, self.height as i64);
        if w == 0 || h == 0 {
            return Vec4::ZERO;
        }
        let i = (y.rem_euclid(h) * w + x.rem_euclid(w)) as usize;
        self.texels
            .get(i)
            .copied()
            .map_or(Vec4::ZERO, Vec4::from_array)
    }

    /// Bilinear lookup with repeat wrap; texel centres at (i + ½)/size, as on the GPU.
    pub fn sample_bilinear(&self, uv: Vec2) -> Vec4 {
        let p = uv * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        if !p.is_finite() {
            return self.texel(0, 0);
        }
        let (w, h) = (self.width as i64, self.height as i64);
        if w == 0 || h == 0 {
            return Vec4::ZERO;
        }
        let f = p.floor();
        let t = p - f;
        // Wrap once per axis (the tracer calls this per shading point; `%` is slow).
        let x0 = (f.x as i64).rem_euclid(w) as usize;
        let y0 = (f.y as i64).rem_euclid(h) as usize;
        let x1 = if x0 + 1 == w as usize { 0 } else { x0 + 1 };
        let y1 = if y0 + 1 == h as usize { 0 } else { y0 + 1 };
        let at = |x: usize, y: usize| {
            self.texels
                .get(y * w as usize + x)
                .copied()
                .map_or(Vec4::ZERO, Vec4::from_array)
        };
        let top = at(x0, y0).lerp(at(x1, y0), t.x);
        let bottom = at(x0, y1).lerp(at(x1, y1), t.x);
        top.lerp(bottom, t.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BLACK_WHITE: [Vec3; 2] = [Vec3::ZERO, Vec3::ONE];

    #[test]
    fn checker_has_four_checks_and_is_anti_aliased() {
        let t = Texture::bake("c", Pattern::Checker, BLACK_WHITE, 0.0, 64);
        assert_eq!(t.texels.len(), 64 * 64);
        assert_eq!(t.texel(10, 10), Vec4::new(0.0, 0.0, 0.0, 1.0));
        assert_eq!(t.texel(40, 10), Vec4::ONE);
        assert_eq!(t.texel(10, 40), Vec4::ONE);
        assert_eq!(t.texel(40, 40), Vec4::new(0.0, 0.0, 0.0, 1.0));
        let mean: f32 = t.texels.iter().map(|c| c[0]).sum::<f32>() / t.texels.len() as f32;
        assert!((mean - 0.5).abs() < 1e-6);
    }

    #[test]
    fn grid_and_bricks_cover_the_expected_fraction() {
        // Grid lines of width w along both borders cover 1 − (1 − w)² of the tile.
        let w = 0.1;
        let g = Texture::bake("g", Pattern::Grid, BLACK_WHITE, w, 200);
        let line: f32 = g.texels.iter().map(|c| c[0]).sum::<f32>() / g.texels.len() as f32;
        assert!(
            (line - (1.0 - (1.0 - w) * (1.0 - w))).abs() < 1e-3,
            "{line}"
        );
        let b = Texture::bake("b", Pattern::Bricks, BLACK_WHITE, 0.05, 200);
        let mortar: f32 = b.texels.iter().map(|c| c[0]).sum::<f32>() / b.texels.len() as f32;
        // 10 % of each course's width and 20 % of its height are joint: 1 − 0.9·0.8.
        assert!((mortar - 0.28).abs() < 0.01, "{mortar}");
    }

    #[test]
    fn bilinear_wraps_and_stays_finite() {
        let t = Texture::bake("c", Pattern::Checker, BLACK_WHITE, 0.0, 8);
        assert_eq!(t.sample_bilinear(Vec2::new(0.0625, 0.0625)), t.texel(0, 0));
        assert_eq!(t.sample_bilinear(Vec2::new(1.0625, -0.9375)), t.texel(0, 0));
        // At the tile corner the four wrapped neighbours average.
        assert!((t.sample_bilinear(Vec2::ZERO).x - 0.5).abs() < 1e-6);
        assert!(t.sample_bilinear(Vec2::new(f32::NAN, 1e30)).is_finite());
        let empty = Texture {
            name: String::new(),
            width: 0,
            height: 0,
            texels: vec![],
            pattern: None,
        };
        assert_eq!(empty.sample_bilinear(Vec2::ONE), Vec4::ZERO);
    }
}
