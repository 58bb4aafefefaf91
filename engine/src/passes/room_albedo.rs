//! A diffuse surface's albedo as the room pass draws it
//! (`shaders/albedo.glsl`): the push-constant fields and pipeline variant
//! of a material. Shared by the room passes and by the light-map solve,
//! which renders the same albedo as its known factor.

use glam::{Vec3, Vec4};
use inference::scene::Texture;

/// The values of `albedo.glsl`'s `PATTERN`, one pipeline variant each:
/// variant `i` draws pattern `i` (0 reads the bound texture).
pub const PATTERN_VARIANTS: [u32; 4] = [0, 1, 2, 3];

/// The push-constant fields `albedo` and `pattern` and the variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceAlbedo {
    /// rgb albedo × colors[0] (or the albedo the texture modulates); a the
    /// pattern's line width.
    pub first: Vec4,
    /// rgb albedo × colors[1]; a the baked texel in tiles.
    pub second: Vec4,
    pub variant: usize,
}

impl SurfaceAlbedo {
    /// A material of albedo `albedo` with `texture`: drawn in closed form
    /// when the texture was baked from a pattern, else read from it (a
    /// white texel stands for no texture).
    pub fn of(albedo: Vec3, texture: Option<&Texture>) -> Self {
        match texture.and_then(|t| t.pattern.map(|p| (t.width, p))) {
            Some((width, p)) => Self {
                first: (albedo * p.colors[0]).extend(p.line_width),
                second: (albedo * p.colors[1]).extend(1.0 / width.max(1) as f32),
                variant: p.pattern.shader_id() as usize,
            },
            None => Self {
                first: albedo.extend(1.0),
                second: Vec4::ZERO,
                variant: 0,
            },
        }
    }

    /// Whether the draw reads the bound texture (else it is white-bound).
    pub fn reads_texture(&self) -> bool {
        self.variant == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use inference::scene::Pattern;

    #[test]
    fn patterns_pick_their_variant_and_images_read_the_texture() {
        let colors = [Vec3::new(0.8, 0.78, 0.72), Vec3::new(0.08, 0.09, 0.12)];
        let t = Texture::bake("floor", Pattern::Checker, colors, 0.0, 64);
        let s = SurfaceAlbedo::of(Vec3::new(1.0, 0.5, 1.0), Some(&t));
        assert_eq!(s.variant, 1);
        assert!(!s.reads_texture());
        assert_eq!(PATTERN_VARIANTS[s.variant], Pattern::Checker.shader_id());
        assert_eq!(s.first, Vec4::new(0.8, 0.39, 0.72, 0.0));
        assert_eq!(s.second.w, 1.0 / 64.0);
        let image = Texture { pattern: None, ..t };
        let s = SurfaceAlbedo::of(Vec3::splat(0.5), Some(&image));
        assert_eq!((s.variant, s.first), (0, Vec4::new(0.5, 0.5, 0.5, 1.0)));
        assert!(s.reads_texture());
        assert_eq!(SurfaceAlbedo::of(Vec3::ONE, None).variant, 0);
        for p in [Pattern::Checker, Pattern::Bricks, Pattern::Grid] {
            assert!(PATTERN_VARIANTS.contains(&p.shader_id()));
        }
    }
}
