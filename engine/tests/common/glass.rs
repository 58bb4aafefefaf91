//! The glass scene and shell maps the glass device tests share.

use std::path::Path;

use inference::scene::Scene;

/// The glass scene with `edits` applied, written into `dir` as `name`.
pub fn glass_scene(dir: &Path, name: &str, edits: &[(&str, &str)]) -> Scene {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes/glass.toml");
    let mut text = std::fs::read_to_string(source).expect("glass.toml");
    for (from, to) in edits {
        assert!(text.contains(from), "glass.toml lacks {from:?}");
        text = text.replacen(from, to, 1);
    }
    // Plain colours instead of textures: a rasterised cube capture blurs
    // textures seen at grazing angles (no anisotropic filtering), which is
    // the capture's limit, not the lookups' this test is about.
    let colours = ["[0.7, 0.3, 0.2]", "[0.2, 0.6, 0.3]", "[0.3, 0.4, 0.8]"];
    let mut albedos = colours.iter();
    text = text
        .lines()
        .filter(|l| !l.starts_with("texture ="))
        .map(
            |l| match (l.starts_with("albedo ="), albedos.clone().next()) {
                (true, Some(c)) => {
                    albedos.next();
                    format!("albedo = {c}")
                }
                _ => l.to_string(),
            },
        )
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("write scene");
    Scene::load(path.to_str().expect("utf-8 path")).expect("scene")
}

/// PSNR over the pixels of `mask`.
pub fn masked_psnr(a: &[[f32; 4]], b: &[[f32; 4]], mask: &[bool]) -> f64 {
    let pick = |x: &[[f32; 4]]| -> Vec<[f32; 4]> {
        x.iter()
            .zip(mask)
            .filter(|(_, m)| **m)
            .map(|(p, _)| *p)
            .collect()
    };
    engine::compare::psnr(&pick(a), &pick(b))
}

/// A shell map of `size`² per face, every texel of every level `rgb`
/// (f16 RGBA bytes, as the per-sample maps are stored).
pub fn constant_map(size: u32, rgb: [f32; 3]) -> Vec<u8> {
    constant_rgba(size, [rgb[0], rgb[1], rgb[2], 1.0])
}

/// [`constant_map`] with alpha (premultiplied, as inner layers are stored).
pub fn constant_rgba(size: u32, rgba: [f32; 4]) -> Vec<u8> {
    let texels: u32 = (0..=size.ilog2()).map(|l| 6 * (size >> l).pow(2)).sum();
    let texel = rgba.map(half::f16::from_f32);
    (0..texels)
        .flat_map(|_| texel)
        .flat_map(half::f16::to_le_bytes)
        .collect()
}
