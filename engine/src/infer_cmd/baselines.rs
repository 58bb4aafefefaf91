//! The baselines least squares is measured against, and the pictures
//! that compare them.

use crate::probe::VulkanProbe;
use anyhow::Result;
use glam::Vec3;
use inference::infer::{LayerResult, Target};
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::{Material, Scene};
use inference::solve::layout::{TextureLayout, TextureShape};
use std::path::Path;

/// target | least squares | forward mapping, cropped to the object's
/// bounding box (RGB, premultiplied for RGBA layers), sRGB PNG.
pub(super) fn write_comparison(
    path: &Path,
    width: u32,
    target: &[[f32; 4]],
    r: &LayerResult,
) -> Result<()> {
    let (Some(x0), Some(x1)) = (
        r.pixels.iter().map(|p| p % width).min(),
        r.pixels.iter().map(|p| p % width).max(),
    ) else {
        return Ok(()); // nothing visible, nothing to show
    };
    let (y0, y1) = (r.pixels[0] / width, r.pixels[r.pixels.len() - 1] / width);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let gap = 4;
    let total = 3 * w + 2 * gap;
    let mut out = vec![[0.0f32; 4]; (total * h) as usize];
    let object: std::collections::HashSet<u32> = r.pixels.iter().copied().collect();
    for (panel, image) in [target, &r.rendered_least_squares, &r.rendered_forward]
        .into_iter()
        .enumerate()
    {
        for y in 0..h {
            for x in 0..w {
                let p = (y0 + y) * width + x0 + x;
                if object.contains(&p) {
                    out[(y * total + panel as u32 * (w + gap) + x) as usize] = image[p as usize];
                }
            }
        }
    }
    crate::capture::write_png(path, total, h, &out)?;
    Ok(())
}

/// Each reflector's static EM from the engine (size, origin, texels).
pub(super) type StaticEm = (u32, Vec3, Vec<[f32; 4]>);

pub(super) fn static_ems(
    device: &crate::backend::Device,
    scene: &Scene,
    width: u32,
    height: u32,
) -> Result<std::collections::HashMap<String, StaticEm>> {
    let mut renderer = crate::renderer::Renderer::new(device, scene, width, height)?;
    let reflectors = scene.objects.iter().filter(|o| {
        matches!(
            scene.materials.get(o.material),
            Some(Material::Mirror { .. } | Material::Glossy { .. })
        )
    });
    let mut out = std::collections::HashMap::new();
    for (index, object) in reflectors.enumerate() {
        out.insert(object.name.clone(), renderer.static_em(index)?);
    }
    Ok(out)
}

/// PSNR of `mesh` rendered with the static EM (sphere-at-infinity texgen,
/// as the static-EM frame does) against `target` over `pixels`, through the
/// probe renderer so it is the same device path as the other baselines.
pub(super) fn static_em_psnr(
    probe: &mut VulkanProbe,
    view: &ProbeGeometry,
    mesh: &inference::scene::Mesh,
    (size, _origin, texels): &StaticEm,
    eye: Vec3,
    target: &Target,
    pixels: &[u32],
) -> Result<f64> {
    let mut lookups = vec![[0.0f32; 4]; mesh.positions.len()];
    inference::texgen::sphere_at_infinity(eye, &mesh.positions, &mesh.normals, &mut lookups);
    let geometry = ProbeGeometry {
        key: view.key ^ 0x5EED_57A7_1CE0_0000,
        lookup: Lookup::Cube(
            lookups
                .iter()
                .map(|l| Vec3::new(l[0], l[1], l[2]))
                .collect(),
        ),
        ..view.clone()
    };
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: *size });
    let image = inference::probe::ProbeRenderer::render(probe, &geometry, &layout, texels)?;
    Ok(inference::infer::layer::psnr_over_rows(
        &image, target, pixels,
    ))
}
