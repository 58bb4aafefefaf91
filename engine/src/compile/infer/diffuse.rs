//! `engine infer --diffuse`: one view-independent texture from several
//! views, stacked into one solve.

use super::InferRequest;
use super::report::finite_or_max;
use super::targets::target_pixels;
use crate::compile::trace::traced_layers;
use crate::maps::traced_stem;
use crate::probe::VulkanProbe;
use crate::util::files::claim_dir;
use anyhow::{Context, Result, bail};
use inference::infer::Target;
use inference::infer::maps::write_map;
use inference::infer::stacked::StackedResult;
use inference::key::Key;
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::{Material, Object, Scene};
use inference::solve::SolveOptions;
use inference::solve::layout::TextureShape;
use inference::trace::{TraceSettings, Tracer, cache, camera};
use serde::Serialize;

#[derive(Serialize)]
pub struct DiffuseReport {
    pub object: String,
    pub views: Vec<u32>,
    pub rows: usize,
    pub probe_renders: u32,
    pub psnr_per_view_db: Vec<f64>,
    pub cg_iterations: Vec<u32>,
    pub solve_s: f64,
}

/// Texture coordinates that give every surface point its own texel, which
/// a view-independent texture needs (tiled UVs would force one tile to hold
/// the lighting of the whole surface). A flat object is projected onto its
/// plane, normalised to [0, 1]²; otherwise its own UVs are kept.
pub(super) fn unique_uvs(mesh: &inference::scene::Mesh) -> Vec<glam::Vec2> {
    let (lo, hi) = mesh.bounds();
    let size = hi - lo;
    let flat = size.min_element() <= 1e-4 * size.max_element();
    if !flat {
        return mesh.uvs.clone();
    }
    let thin = if size.x <= size.y.min(size.z) {
        0
    } else if size.y <= size.z {
        1
    } else {
        2
    };
    let (u, v) = [(1, 2), (0, 2), (0, 1)][thin];
    mesh.positions
        .iter()
        .map(|p| glam::Vec2::new((p[u] - lo[u]) / size[u], (p[v] - lo[v]) / size[v]))
        .collect()
}

/// One view-independent texture of a diffuse object from several views.
#[derive(Clone, Debug)]
pub struct DiffuseRequest {
    pub object: String,
    /// Orbit samples stacked into the solve.
    pub views: Vec<u32>,
    /// Texture size (square, power of two).
    pub texture_size: u32,
    /// Where to trace and write (its `samples` are ignored).
    pub common: InferRequest,
}

/// One texture for all `req.views`, stacked into one solve.
pub fn infer_diffuse(scene: &Scene, req: &DiffuseRequest) -> Result<String> {
    let object = checked_diffuse_object(scene, req)?;
    let args = &req.common;
    let tracer = Tracer::new(scene)?;
    let (width, height) = args.size;
    let settings = args.trace_settings()?;
    let out = &args.infer_dir;
    claim_dir(out)?;
    let scene_key = cache::scene_key(scene);
    let device = crate::backend::create_device(&args.device)?;
    let mut probe = VulkanProbe::new(&device)?;
    let projection = camera::projection(scene, width, height);
    let layer = format!("{}.diffuse", req.object);
    let uvs = unique_uvs(&object.mesh);
    let targets = traced_targets(&tracer, &scene_key, &settings, req, &layer)?;
    let views: Vec<(ProbeGeometry, Target)> = req
        .views
        .iter()
        .zip(&targets)
        .map(|(&k, pixels)| -> Result<_> {
            let eye = tracer.sample_eye(k)?;
            Ok((
                ProbeGeometry {
                    key: u64::from(k) + 1,
                    positions: object.mesh.positions.clone(),
                    indices: object.mesh.indices.clone(),
                    lookup: Lookup::Uv(uvs.clone()),
                    view_proj: projection * scene.orbit.view(eye),
                    width,
                    height,
                },
                Target {
                    name: &layer,
                    pixels,
                    channels: 3,
                },
            ))
        })
        .collect::<Result<_>>()?;
    let options = SolveOptions {
        eps_f: args.eps_f,
        ..SolveOptions::default()
    };
    let shape = TextureShape::Tex2D {
        width: req.texture_size,
        height: req.texture_size,
    };
    let result = inference::infer::stacked::infer_stacked(&mut probe, &views, shape, &options)
        .with_context(|| format!("stacked solve for {layer}"))?;
    write_map(
        &out.join(format!("{layer}.exr")),
        &result.layout,
        &result.map,
    )?;
    let report = DiffuseReport::new(req, &result);
    crate::util::files::write_json(&out.join("diffuse_report.json"), &report)?;
    Ok(report.summary_line(&layer))
}

/// The object `req` names, checked before any file is touched: it exists
/// and is diffuse, the texture size is a power of two up to 4096, every
/// view is an orbit sample.
fn checked_diffuse_object<'s>(scene: &'s Scene, req: &DiffuseRequest) -> Result<&'s Object> {
    let object_name = req.object.as_str();
    let object = scene.object(object_name).with_context(|| {
        let diffuse: Vec<&str> = (scene.objects.iter())
            .filter(|o| {
                matches!(
                    scene.materials.get(o.material),
                    Some(Material::Diffuse { .. })
                )
            })
            .map(|o| o.name.as_str())
            .collect();
        format!(
            "--diffuse {object_name}: no such object in {} (its diffuse objects: {})",
            scene.origin,
            diffuse.join(", ")
        )
    })?;
    if !matches!(
        scene.materials.get(object.material),
        Some(Material::Diffuse { .. })
    ) {
        bail!(
            "--diffuse {object_name}: the object's material is not diffuse (expected a Lambertian object)"
        );
    }
    let size = req.texture_size;
    if size == 0 || !size.is_power_of_two() || size > 4096 {
        bail!("--texture-size {size}: expected a power of two up to 4096");
    }
    if let Some(&k) = req.views.iter().find(|&&k| k >= scene.orbit.sample_count()) {
        bail!(
            "--views: sample {k} out of range 0..{} (orbit.samples × orbit.rings)",
            scene.orbit.sample_count()
        );
    }
    Ok(object)
}

/// The traced pixels of `layer` in every view of `req` (traced first where
/// missing or stale).
fn traced_targets(
    tracer: &Tracer,
    scene_key: &Key,
    settings: &TraceSettings,
    req: &DiffuseRequest,
    layer: &str,
) -> Result<Vec<Vec<[f32; 4]>>> {
    let args = &req.common;
    let (width, height) = args.size;
    let mut targets = Vec::new();
    for &k in &req.views {
        let stem = traced_stem(&args.trace_dir, k);
        let eye = tracer.sample_eye(k)?;
        let (layers, _) = traced_layers(tracer, scene_key, eye, settings, &stem)?;
        targets.push(target_pixels(
            &layers,
            layer,
            false,
            width as usize * height as usize,
        )?);
    }
    Ok(targets)
}

impl DiffuseReport {
    fn new(req: &DiffuseRequest, result: &StackedResult) -> Self {
        Self {
            object: req.object.clone(),
            views: req.views.clone(),
            rows: result.rows,
            probe_renders: result.probe_renders,
            psnr_per_view_db: result
                .psnr_per_view_db
                .iter()
                .map(|&v| finite_or_max(v))
                .collect(),
            cg_iterations: result.iterations.clone(),
            solve_s: result.solve_time.as_secs_f64(),
        }
    }

    /// The line `engine infer --diffuse` prints.
    fn summary_line(&self, layer: &str) -> String {
        format!(
            "{layer}: {} views stacked, {} rows, {} probe renders, PSNR per view {:?} dB, solve {:.2} s ({:?} CG it.)\n",
            self.views.len(),
            self.rows,
            self.probe_renders,
            self.psnr_per_view_db
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>(),
            self.solve_s,
            self.cg_iterations
        )
    }
}
