//! One diffuse object's light map from the stacked traced views: per view,
//! the target is the tracer's diffuse layer of the object (soft shadows,
//! indirect light, caustics and the light's true shape included), the rows
//! are the pixels the object covers whole, and the known factor is the
//! albedo the device itself draws there (the room passes' albedo shader:
//! a pattern filtered in closed form, or the texture through their sampler).

use crate::compile::CompileContext;
use crate::compile::infer::targets::target_pixels;
use crate::compile::trace::traced_layers;
use crate::gpu_scene::mip_chain;
use crate::passes::room_albedo::SurfaceAlbedo;
use crate::probe::VulkanProbe;
use anyhow::{Context, Result, bail};
use glam::Vec2;
use inference::infer::factored::{FactoredResult, FactoredView, infer_factored};
use inference::key::Key;
use inference::lightmap::{ObjectLightmap, ObjectSight, Viewpoint};
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::{Material, Scene};
use inference::solve::SolveOptions;
use inference::solve::layout::{TextureLayout, TextureShape};
use inference::trace::{TraceSettings, Tracer, cache, camera, output};
use std::path::{Path, PathBuf};

/// Coverage from which a traced pixel is the object's alone (a row).
const WHOLE: f32 = 0.999;

pub struct Solver<'a> {
    scene: &'a Scene,
    tracer: Tracer<'a>,
    scene_key: Key,
    settings: TraceSettings,
    trace_dir: PathBuf,
    probe: VulkanProbe,
    options: SolveOptions,
    /// Traced layers of each stacked view, read once.
    traced: Vec<(Viewpoint, Vec<output::ExrLayer>)>,
}

/// A solved light map and its one-line report.
pub struct Solved {
    pub result: FactoredResult,
    pub summary: String,
}

/// One view's inputs, owned.
struct ViewData {
    name: String,
    geometry: ProbeGeometry,
    target: Vec<[f32; 4]>,
    factor: Vec<[f32; 4]>,
    usable: Vec<bool>,
}

impl<'a> Solver<'a> {
    pub fn new(
        ctx: &CompileContext<'a>,
        settings: &TraceSettings,
        dir: &Path,
        options: SolveOptions,
    ) -> Result<Self> {
        let device = crate::backend::create_device(ctx.device)?;
        Ok(Self {
            scene: ctx.scene,
            tracer: Tracer::new(ctx.scene)?,
            scene_key: cache::scene_key(ctx.scene),
            settings: settings.clone(),
            trace_dir: dir.join("trace"),
            probe: VulkanProbe::new(&device)?,
            options,
            traced: Vec::new(),
        })
    }

    /// The traced layers of `view` (traced first when missing or stale).
    fn layers(&mut self, view: Viewpoint) -> Result<&[output::ExrLayer]> {
        let i = match self.traced.iter().position(|(v, _)| *v == view) {
            Some(i) => i,
            None => {
                let stem = self.trace_dir.join(format!(
                    "view_az{:+.3}_el{:+.3}",
                    view.azimuth_deg, view.elevation_deg
                ));
                let eye = view.eye(&self.scene.orbit);
                let (layers, _) =
                    traced_layers(&self.tracer, &self.scene_key, eye, &self.settings, &stem)?;
                self.traced.push((view, layers));
                self.traced.len() - 1
            }
        };
        Ok(&self.traced[i].1)
    }

    /// One stacked view of `object`: its traced target and rows, the albedo
    /// the device samples at each pixel, and the light-map geometry.
    fn view_data(
        &mut self,
        object: usize,
        light_uvs: &[Vec2],
        view: Viewpoint,
    ) -> Result<ViewData> {
        let scene = self.scene;
        let o = &scene.objects[object];
        let Some(Material::Diffuse { albedo, texture }) = scene.materials.get(o.material) else {
            bail!("{}: a light map needs a diffuse material", o.name);
        };
        let surface = SurfaceAlbedo::of(*albedo, texture.and_then(|t| scene.textures.get(t)));
        // A pattern is drawn in closed form: its baked texels are not read,
        // so neither their MIP chain nor their upload is made.
        let read = texture.filter(|_| surface.reads_texture());
        let (albedo_layout, albedo_texels) = albedo_texture(scene, read);
        let (width, height) = (self.settings.width, self.settings.height);
        let n = width as usize * height as usize;
        let view_proj =
            camera::projection(scene, width, height) * scene.orbit.view(view.eye(&scene.orbit));
        // One key per mesh and lookup (the probe keeps the uploaded mesh).
        let key = 2 * object as u64 + 1;
        let geometry = |key: u64, lookup: Lookup| ProbeGeometry {
            key,
            positions: o.mesh.positions.clone(),
            indices: o.mesh.indices.clone(),
            lookup,
            view_proj,
            width,
            height,
        };
        let factor = self
            .probe
            .render_albedo(
                &geometry(key, Lookup::Uv(o.mesh.uvs.clone())),
                &albedo_layout,
                &albedo_texels,
                surface,
            )?
            .iter()
            .map(|s| [s[0], s[1], s[2], 1.0])
            .collect();
        let name = format!(
            "{}.diffuse at az {:+} el {:+}",
            o.name, view.azimuth_deg, view.elevation_deg
        );
        let layers = self.layers(view)?;
        let target = target_pixels(layers, &format!("{}.diffuse", o.name), false, n)
            .with_context(|| name.clone())?;
        let usable = coverage(layers, &o.name, n)?
            .iter()
            .map(|&c| c >= WHOLE)
            .collect();
        Ok(ViewData {
            name,
            // The room pass reads light maps from the nearest MIP level.
            geometry: geometry(key + 1, Lookup::UvNearestLevel(light_uvs.to_vec())),
            target,
            factor,
            usable,
        })
    }

    /// `sight`'s object's light map laid out as `plan`, from `views`.
    pub fn solve(
        &mut self,
        sight: &ObjectSight,
        plan: &ObjectLightmap,
        views: &[Viewpoint],
    ) -> Result<Solved> {
        let object = &self.scene.objects[sight.object];
        let light_uvs = plan.uvs(&sight.charts);
        let data = views
            .iter()
            .map(|&view| self.view_data(sight.object, &light_uvs, view))
            .collect::<Result<Vec<_>>>()?;
        let stacked: Vec<FactoredView> = data
            .iter()
            .map(|d| FactoredView {
                name: &d.name,
                geometry: d.geometry.clone(),
                target: &d.target,
                factor: &d.factor,
                usable: &d.usable,
            })
            .collect();
        let shape = TextureShape::Tex2D {
            width: plan.width,
            height: plan.height,
        };
        let result = infer_factored(&mut self.probe, &stacked, shape, &self.options)
            .with_context(|| format!("light map of {}", object.name))?;
        let summary = format!(
            "{}: {}×{} light map ({:.0} texels/m by the rule), {} views, {} rows, {} probe renders, PSNR per view [{}] dB (— where it has no rows), probes {:.1} s, solve {:.1} s",
            object.name,
            plan.width,
            plan.height,
            plan.rule_texels_per_metre,
            views.len(),
            result.rows,
            result.probe_renders,
            result
                .psnr_per_view_db
                .iter()
                .zip(&result.rows_per_view)
                .map(|(v, rows)| if rows.is_empty() {
                    "—".to_owned()
                } else {
                    format!("{v:.1}")
                })
                .collect::<Vec<_>>()
                .join(", "),
            result.probe_time.as_secs_f64(),
            result.solve_time.as_secs_f64(),
        );
        Ok(Solved { result, summary })
    }
}

/// The material's texture as the device samples it (its box-filtered MIP
/// chain, as `gpu_scene` uploads it), or one white texel.
fn albedo_texture(scene: &Scene, texture: Option<usize>) -> (TextureLayout, Vec<[f32; 4]>) {
    let (w, h, texels) = match texture.and_then(|t| scene.textures.get(t)) {
        Some(t) => (t.width, t.height, t.texels.clone()),
        None => (1, 1, vec![[1.0; 4]]),
    };
    let layout = TextureLayout::full_chain(TextureShape::Tex2D {
        width: w,
        height: h,
    });
    (layout, mip_chain(w, h, &texels).concat())
}

/// The traced coverage of `object` (`<object>.mask`) at every pixel.
fn coverage(layers: &[output::ExrLayer], object: &str, n: usize) -> Result<Vec<f32>> {
    let name = format!("{object}.mask");
    let (_, channels) = layers
        .iter()
        .find(|(l, _)| *l == name)
        .with_context(|| format!("traced image has no layer {name:?}"))?;
    let Some((_, y)) = channels.first() else {
        bail!("layer {name:?}: expected one channel Y");
    };
    if y.len() != n {
        bail!("layer {name:?}: {} pixels, expected {n}", y.len());
    }
    Ok(y.clone())
}
