//! The static-EM baseline: the engine's own static cube map, read back and
//! rendered on the reflector like the other maps.

use crate::probe::VulkanProbe;
use anyhow::Result;
use glam::Vec3;
use inference::infer::Target;
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::Scene;
use inference::solve::layout::{TextureLayout, TextureShape};

/// Each reflector's static EM from the engine (size, origin, texels).
pub(super) type StaticEm = (u32, Vec3, Vec<[f32; 4]>);

pub(super) fn static_ems(
    device: &crate::backend::Device,
    scene: &Scene,
    width: u32,
    height: u32,
) -> Result<std::collections::HashMap<String, StaticEm>> {
    let mut renderer = crate::renderer::Renderer::new(device, scene, width, height)?;
    let reflectors = scene
        .objects
        .iter()
        .filter(|o| crate::maps::reflective(scene, o));
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
        // The static EM is played without a bias.
        lookup: Lookup::Cube {
            dirs: lookups
                .iter()
                .map(|l| Vec3::new(l[0], l[1], l[2]))
                .collect(),
            lod_bias: 0.0,
        },
        ..view.clone()
    };
    let layout = TextureLayout::full_chain(TextureShape::Cube { size: *size });
    let image = inference::probe::ProbeRenderer::render(probe, &geometry, &layout, texels)?;
    Ok(inference::infer::layer::psnr_over_rows(
        &image, target, pixels,
    ))
}
