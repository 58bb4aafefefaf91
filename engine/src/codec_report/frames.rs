//! Rendered-frame PSNR of a container: every reflector's distant layer
//! decoded and rendered on the reflector by this device, against the
//! traced layer and against the uncompressed map rendered the same way.

use super::CodecReportRequest;
use crate::maps::{MapLayer, map_path, map_specs, traced_stem};
use crate::util::stats::median;
use anyhow::{Context, Result};
use inference::infer::maps::read_map;
use inference::scene::Scene;
use inference::solve::layout::TextureLayout;
use inference::trace::output;

/// One measured frame: a reflector's distant layer at one orbit sample.
pub(super) struct FrameItem {
    /// Texture index in the container (= object index of [`map_specs`]).
    pub(super) index: u32,
    pub(super) k: u32,
    name: String,
    layout: TextureLayout,
    geometry: inference::probe::ProbeGeometry,
    /// The traced layer.
    target: Vec<[f32; 4]>,
    /// The reflector's pixels: rendered coverage above one half.
    pub(super) pixels: Vec<u32>,
    /// The uncompressed map rendered, against the traced layer.
    raw_db: f64,
    /// That render (the reference for compression alone).
    raw_render: Vec<[f32; 4]>,
}

/// Rendered-frame PSNR, set up once: every reflector's distant layer at
/// every `every`-th sample with a traced target, rendered on the reflector
/// by this device (box texgen, as inferred) from a map, against the traced
/// layer over the object's pixels (coverage > 0.5), RGB, peak = the traced
/// layer's maximum there; medians over frames.
pub(super) struct FrameBench {
    probe: crate::probe::VulkanProbe,
    pub(super) items: Vec<FrameItem>,
    /// The first item's decoded map, for [`FrameBench::render_load`].
    load_map: Option<Vec<[f32; 4]>>,
}

/// How [`FrameBench`] pools pixels, for the JSON.
pub(super) const FRAME_PIXELS: &str = "the reflector's pixels (rendered coverage > 0.5) at every --frames-every-th orbit sample; linear RGB; PSNR per frame with peak = the traced image's maximum over those pixels; median over frames";

impl FrameBench {
    pub(super) fn new(req: &CodecReportRequest, scene: &Scene) -> Result<Option<Self>> {
        use inference::infer::Target;
        use inference::probe::ProbeRenderer;
        if req.frames_every == 0 {
            return Ok(None);
        }
        let (width, height) = req.size;
        let device = crate::backend::create_device(&req.device)?;
        let mut probe = crate::probe::VulkanProbe::new(&device)?;
        let projection = inference::trace::camera::projection(scene, width, height);
        let mut items = Vec::new();
        for (index, spec) in map_specs(scene).iter().enumerate() {
            if spec.layer != MapLayer::Distant {
                continue;
            }
            let Some(object) = scene.object(&spec.object) else {
                continue;
            };
            let layout = spec.layout();
            for k in (0..scene.orbit.sample_count()).step_by(req.frames_every as usize) {
                let traced = output::with_suffix(&traced_stem(&req.trace_dir, k), ".exr");
                if !traced.is_file() {
                    continue;
                }
                let layers = output::read_exr(&traced)?;
                let name = spec.name();
                let target = crate::compile::infer::targets::target_pixels(
                    &layers,
                    &name,
                    false,
                    (width * height) as usize,
                )
                .with_context(|| format!("{}", traced.display()))?;
                let geometry = distant_geometry(scene, object, k, projection, (width, height))?;
                let path = map_path(&req.infer_dir, k, &spec.object, spec.layer);
                // Alpha 1 everywhere, like the decoded maps: the rendered
                // alpha is the object's coverage either way.
                let raw =
                    inference::infer::layer::texels(&read_map(&path, &layout, 3)?, layout.len());
                let render_raw = probe.render(&geometry, &layout, &raw)?;
                let pixels: Vec<u32> = (0..width * height)
                    .filter(|&p| render_raw[p as usize][3] > 0.5)
                    .collect();
                let t = Target {
                    name: &name,
                    pixels: &target,
                    channels: 3,
                };
                let raw_db = inference::infer::layer::psnr_over_rows(&render_raw, &t, &pixels);
                items.push(FrameItem {
                    index: index as u32,
                    k,
                    name,
                    layout: layout.clone(),
                    geometry,
                    target,
                    pixels,
                    raw_db,
                    raw_render: render_raw,
                });
            }
        }
        Ok((!items.is_empty()).then_some(Self {
            probe,
            items,
            load_map: None,
        }))
    }

    /// Median PSNRs of the container's decoded maps rendered, over the
    /// frames: against the traced layer, and against the uncompressed maps
    /// rendered (compression alone).
    pub(super) fn decoded_db(&mut self, container: &codec::Container) -> Result<(f64, f64)> {
        use inference::infer::Target;
        use inference::probe::ProbeRenderer;
        let (mut db, mut vs_raw) = (Vec::new(), Vec::new());
        for it in &self.items {
            let mut decoded = vec![0.0f32; it.layout.len() * 4];
            let Some(texture) = container.textures().get(it.index as usize) else {
                anyhow::bail!("the container holds no texture {}", it.index);
            };
            let at = texture.grid.sample_at(it.k);
            codec::decode_leaf_all(container, it.index, 0, at, &mut decoded)?;
            let decoded: Vec<[f32; 4]> = decoded
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], 1.0])
                .collect();
            let render = self.probe.render(&it.geometry, &it.layout, &decoded)?;
            let psnr_against = |pixels| {
                let t = Target {
                    name: &it.name,
                    pixels,
                    channels: 3,
                };
                inference::infer::layer::psnr_over_rows(&render, &t, &it.pixels)
            };
            db.push(psnr_against(&it.target));
            vs_raw.push(psnr_against(&it.raw_render));
        }
        Ok((median(&db), median(&vs_raw)))
    }

    /// Renders frame `i` of a loop over the views of the first item's
    /// reflector with its decoded map (decoded once, on the first call):
    /// device work for timing decodes under load.
    pub(super) fn render_load(&mut self, container: &codec::Container, i: usize) -> Result<()> {
        use inference::probe::ProbeRenderer;
        let first = &self.items[0];
        if self.load_map.is_none() {
            let mut decoded = vec![0.0f32; first.layout.len() * 4];
            let Some(texture) = container.textures().get(first.index as usize) else {
                anyhow::bail!("the container holds no texture {}", first.index);
            };
            // Through the grid: on 2D blocks sample k is not [k, 0].
            let at = texture.grid.sample_at(first.k);
            codec::decode_leaf_all(container, first.index, 0, at, &mut decoded)?;
            self.load_map = Some(
                decoded
                    .chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], 1.0])
                    .collect(),
            );
        }
        let same: Vec<&FrameItem> = self
            .items
            .iter()
            .filter(|it| it.index == first.index)
            .collect();
        let it = same[i % same.len()];
        if let Some(map) = &self.load_map {
            self.probe.render(&it.geometry, &it.layout, map)?;
        }
        Ok(())
    }

    pub(super) fn raw_db(&self) -> f64 {
        median(&self.items.iter().map(|i| i.raw_db).collect::<Vec<_>>())
    }
}

/// The probe geometry of `object`'s distant layer seen from sample `k`:
/// box texgen from its centroid, the traced camera.
fn distant_geometry(
    scene: &Scene,
    object: &inference::scene::Object,
    k: u32,
    projection: glam::Mat4,
    (width, height): (u32, u32),
) -> Result<inference::probe::ProbeGeometry> {
    use inference::em_geometry::{EmGeometry, texgen};
    use inference::probe::{Lookup, ProbeGeometry};
    let (room_min, room_max) = scene.bounds();
    let origin = object.mesh.area_weighted_centroid();
    let eye = scene.orbit.sample_eye(k)?;
    let mut lookups = vec![[0.0f32; 4]; object.mesh.positions.len()];
    let geometry_em = EmGeometry::Box {
        min: room_min,
        max: room_max,
    };
    texgen(
        &geometry_em,
        origin,
        eye,
        &object.mesh.positions,
        &object.mesh.normals,
        &mut lookups,
    );
    Ok(ProbeGeometry {
        key: 0xC0DEC ^ u64::from(k),
        positions: object.mesh.positions.clone(),
        indices: object.mesh.indices.clone(),
        lookup: Lookup::Cube {
            dirs: lookups
                .iter()
                .map(|l| glam::Vec3::new(l[0], l[1], l[2]))
                .collect(),
            lod_bias: object.lod_bias(),
        },
        view_proj: projection * scene.orbit.view(eye),
        width,
        height,
    })
}
