//! One sample's inference: its traced layers, then each map asked for,
//! written with its key record, the sample's report merged after each.

use super::baselines::{StaticEm, static_em_psnr, static_ems};
use super::display_weights::view_weights;
use super::jobs::{Stack, StackedView, stacked_views_of, stacks_above};
use super::pictures::{write_comparison, write_map_picture};
use super::report::{LayerReport, SampleReport, finite_or_max};
use super::targets::{composite_pixels, specular_pixels, target_pixels};
use super::{InferRequest, Job, Plan};
use crate::compile::trace::traced_layers;
use crate::maps::{MapLayer, map_path, sample_dir, traced_stem, view_stem};
use crate::probe::VulkanProbe;
use crate::util::files::claim_dir;
use anyhow::{Context, Result};
use glam::{Mat4, Vec3};
use inference::em_geometry::{EmGeometry, texgen};
use inference::infer::maps::{read_map, write_map};
use inference::infer::{MatrixCache, Target, View, Views, infer_layer_with};
use inference::key::Key;
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::Mesh;
use inference::trace::{Tracer, camera, output};
use std::collections::HashMap;

/// Samples per warm chain: inside a chain each sample's solve starts from
/// the previous sample's map (fewer iterations), the first starts cold, so
/// a shard of whole chains (`engine compile --shard`) infers exactly the
/// bits one process would.
pub const WARM_CHAIN: u32 = 10;

/// What every sample of a run shares: the plan, the device's probe
/// renderer, the static EMs (a baseline), the tracer for missing targets.
pub(super) struct SampleRun<'a> {
    plan: &'a Plan<'a>,
    req: &'a InferRequest,
    probe: VulkanProbe,
    static_ems: HashMap<String, StaticEm>,
    tracer: Tracer<'a>,
    projection: Mat4,
    /// Each view's rendering matrix, kept while the neighbouring samples
    /// that stack it are solved.
    matrices: MatrixCache,
}

impl<'a> SampleRun<'a> {
    pub(super) fn new(
        plan: &'a Plan<'a>,
        req: &'a InferRequest,
        device: &crate::backend::Device,
        tracer: Tracer<'a>,
    ) -> Result<Self> {
        let (width, height) = req.size;
        Ok(Self {
            plan,
            req,
            probe: VulkanProbe::new(device)?,
            static_ems: static_ems(device, plan.scene, width, height)?,
            tracer,
            projection: camera::projection(plan.scene, width, height),
            // A sample's solve of each job may stack three views on its ring
            // (its own and one either side; the next sample reuses two of
            // them) and those above it.
            matrices: MatrixCache::new(
                plan.jobs
                    .iter()
                    .map(|j| 3 + j.neighbour_above_deg().len())
                    .sum(),
            ),
        })
    }

    /// Infers the maps `jobs` (indices into the plan's jobs) of sample `k`;
    /// returns the sample's merged report and one printed line per map.
    pub(super) fn infer_sample(
        &mut self,
        k: u32,
        jobs: &[usize],
        bar: &indicatif::ProgressBar,
    ) -> Result<(SampleReport, String)> {
        let own = self.sample_trace(k)?;
        // Traced once per sample, whichever of its jobs stack them.
        let mut around: Vec<(Stack, Vec<StackedTrace>)> = Vec::new();
        for stack in jobs.iter().filter_map(|&i| self.plan.jobs[i].stack()) {
            if !around.iter().any(|(s, _)| *s == stack) {
                bar.set_message(stack_message(k, &stack));
                let traces = self.stacked_traces(k, &stack)?;
                around.push((stack, traces));
            }
        }
        let dir = sample_dir(&self.req.infer_dir, k);
        claim_dir(&dir)?;
        let report_path = dir.join("report.json");
        let order: Vec<String> = self.plan.jobs.iter().map(Job::name).collect();
        let mut report = SampleReport::read_or_new(&report_path, k);
        let mut lines = String::new();
        for &i in jobs {
            let job = &self.plan.jobs[i];
            bar.set_message(format!("sample {k} {}", job.name()));
            let stack = job.stack();
            let stacked = around
                .iter()
                .find(|(s, _)| Some(s) == stack.as_ref())
                .map_or(&[][..], |(_, t)| t);
            let (layer, warm) = self.infer_job(k, job, &own, stacked)?;
            lines += &layer_line(k, &layer);
            report = SampleReport::merged(Some(report), k, vec![layer], warm, &order);
            crate::util::files::write_json(&report_path, &report)?;
            bar.inc(1);
        }
        Ok((report, lines))
    }

    /// Sample `k`'s eye and traced layers (traced first when missing) and
    /// their key.
    fn sample_trace(&self, k: u32) -> Result<SampleTrace> {
        let eye = self.plan.scene.orbit.sample_eye(k)?;
        let stem = traced_stem(&self.req.trace_dir, k);
        let (layers, key) = traced_layers(
            &self.tracer,
            &self.plan.scene_key,
            eye,
            &self.plan.settings,
            &stem,
        )?;
        Ok(SampleTrace { eye, layers, key })
    }

    /// The traces of the views stacked into sample `k`'s solves
    /// ([`stacked_views_of`]), free views traced when missing.
    fn stacked_traces(&self, k: u32, stack: &Stack) -> Result<Vec<StackedTrace>> {
        let orbit = &self.plan.scene.orbit;
        let views = stacked_views_of(orbit, k, stack);
        // The views above come last, one per elevation.
        let above = if stacks_above(orbit, k) {
            stack.above_deg.len()
        } else {
            0
        };
        let first_above = views.len() - above;
        views
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                let trace = match v {
                    StackedView::Sample(n) => self.sample_trace(n)?,
                    StackedView::Free(azimuth, elevation) => {
                        self.free_view_trace(azimuth, elevation)?
                    }
                };
                Ok(StackedTrace::of(trace, i >= first_above))
            })
            .collect()
    }

    /// A free view's traced layers, traced when missing.
    fn free_view_trace(&self, azimuth: f32, elevation: f32) -> Result<SampleTrace> {
        let eye = self.plan.scene.orbit.eye(azimuth, elevation);
        let (layers, key) = traced_layers(
            &self.tracer,
            &self.plan.scene_key,
            eye,
            &self.plan.settings,
            &view_stem(&self.req.trace_dir, azimuth, elevation),
        )?;
        Ok(SampleTrace { eye, layers, key })
    }

    /// The map sample `k`'s solve of `job` starts from: the previous
    /// sample's, when both lie in one warm chain and it is fresh (made from
    /// today's inputs, so by induction the same bits whichever process made
    /// it); None starts cold.
    fn warm_start(
        &self,
        k: u32,
        job: &Job,
        layout: &inference::solve::layout::TextureLayout,
    ) -> Result<Option<Vec<Vec<f32>>>> {
        if k % WARM_CHAIN == 0 {
            return Ok(None);
        }
        let p = k - 1;
        let path = map_path(&self.req.infer_dir, p, &job.object.name, job.layer);
        let key = self.plan.key(p, &self.plan.trace_key(p)?, job);
        if inference::key::freshness(&path, &key) != inference::key::Freshness::Fresh {
            return Ok(None);
        }
        Ok(read_map(&path, layout, job.channels()).ok())
    }

    /// One map: probe renders, solve, baselines; the map, its pictures and
    /// its key record written. `around` holds the traces the job stacks.
    /// Returns its report and whether it was warm-started.
    fn infer_job(
        &mut self,
        k: u32,
        job: &Job,
        own: &SampleTrace,
        around: &[StackedTrace],
    ) -> Result<(LayerReport, bool)> {
        let start = std::time::Instant::now();
        let (width, height) = self.req.size;
        let pixel_count = width as usize * height as usize;
        let name = job.name();
        let mesh = &job.object.mesh;
        let eye = own.eye;
        let pixels = job_target_pixels(job, &own.layers, pixel_count)?;
        let key = self.plan.key(k, &own.key, job);
        let geometry = self.probe_geometry(eye_tag(eye), eye, job, &key);
        let layout = job.layer.layout(job.resolution);
        let previous = self.warm_start(k, job, &layout)?;
        let target = Target {
            name: &name,
            pixels: &pixels,
            channels: job.channels(),
        };
        let neighbours = self.neighbour_views(job, &key, around)?;
        let stacked = stacked_views(job, &neighbours, target);
        let own_weights = view_weights(job, &own.layers, pixel_count)?;
        let views = Views {
            own: View {
                id: view_id(job, eye_tag(eye)),
                geometry: &geometry,
                target,
                weight: 1.0,
                pixel_weights: own_weights.as_deref(),
            },
            neighbours: &stacked,
            cache: &mut self.matrices,
        };
        let result = infer_layer_with(
            &mut self.probe,
            views,
            job.shape(),
            previous.as_deref(),
            &self.plan.options_for(job),
            &mut |_, _| {},
        )
        .with_context(|| {
            let file = output::with_suffix(&traced_stem(&self.req.trace_dir, k), ".exr");
            format!("{}: sample {k}, {name}", file.display())
        })?;
        let dir = sample_dir(&self.req.infer_dir, k);
        let map = map_path(&self.req.infer_dir, k, &job.object.name, job.layer);
        write_map(&map, &layout, &result.map)?;
        // The map's own work (its views' traces have their own records).
        let seconds = Some(start.elapsed().as_secs_f64());
        inference::key::write_record_timed(&map, &key, seconds)?;
        write_comparison(&dir.join(format!("{name}.png")), width, &pixels, &result)?;
        write_map_picture(&dir.join(format!("{name}.map.png")), &layout, &result.map)?;
        let mut report = LayerReport::from(&result);
        // The static EM against the targets it stands for: the distant
        // layer and the whole specular appearance.
        if let (MapLayer::Distant | MapLayer::Sphere, Some(em)) =
            (job.layer, self.static_ems.get(&job.object.name))
        {
            let target = Target {
                channels: 3,
                ..target
            };
            let psnr = static_em_psnr(
                &mut self.probe,
                &geometry,
                mesh,
                em,
                eye,
                &target,
                &result.pixels,
            )?;
            report.psnr_db.static_em = Some(finite_or_max(psnr));
        }
        Ok((report, previous.is_some()))
    }

    /// The views stacked into a sample's solve of an EM layer beside its
    /// own (`[objects.em] neighbour_weight`): the traces `around` it, each
    /// with its own traced target and probe geometry.
    fn neighbour_views(
        &self,
        job: &Job,
        key: &Key,
        around: &[StackedTrace],
    ) -> Result<Vec<NeighbourView>> {
        if job.neighbour_weight() <= 0.0 {
            return Ok(Vec::new());
        }
        let (width, height) = self.req.size;
        let pixel_count = width as usize * height as usize;
        around
            .iter()
            .map(|a| {
                Ok(NeighbourView {
                    tag: a.tag,
                    weight: if a.above {
                        job.neighbour_above_weight()
                    } else {
                        job.neighbour_weight()
                    },
                    geometry: self.probe_geometry(a.tag, a.trace.eye, job, key),
                    pixels: job_target_pixels(job, &a.trace.layers, pixel_count)?,
                    pixel_weights: view_weights(job, &a.trace.layers, pixel_count)?,
                })
            })
            .collect()
    }

    /// The probe renders' geometry of `job` seen from `eye` (tagged `tag`):
    /// the object's mesh with its UVs or, for an EM, its per-vertex cube
    /// lookups.
    fn probe_geometry(&self, tag: u64, eye: Vec3, job: &Job, key: &Key) -> ProbeGeometry {
        let (width, height) = self.req.size;
        let mesh = &job.object.mesh;
        let (positions, indices, lookup) = match (job.geometry, &job.atlas) {
            (Some(g), _) => (
                mesh.positions.clone(),
                mesh.indices.clone(),
                cube_lookup(&g, job.origin, eye, mesh, job.object.lod_bias()),
            ),
            // The PTM: on the object's atlas, as playback draws it.
            (None, atlas) => {
                let m = atlas.as_deref().unwrap_or(mesh);
                (
                    m.positions.clone(),
                    m.indices.clone(),
                    Lookup::Uv(m.uvs.clone()),
                )
            }
        };
        ProbeGeometry {
            key: key.hash() ^ tag,
            positions,
            indices,
            lookup,
            view_proj: self.projection * self.plan.scene.orbit.view(eye),
            width,
            height,
        }
    }
}

/// A sample's eye, its traced layers and their key.
struct SampleTrace {
    eye: Vec3,
    layers: Vec<output::ExrLayer>,
    key: Key,
}

/// A view stacked into a sample's solves: a neighbouring sample's or one
/// traced beside it, tagged by its eye.
struct StackedTrace {
    tag: u64,
    trace: SampleTrace,
    /// One of the views above the sample (`neighbour_above_deg`), weighted
    /// by `neighbour_above_weight`.
    above: bool,
}

impl StackedTrace {
    fn of(trace: SampleTrace, above: bool) -> Self {
        Self {
            tag: eye_tag(trace.eye),
            trace,
            above,
        }
    }
}

/// A view's tag within a run: its eye, so one view stacked into several
/// samples' solves (or some sample's own) probes once while the matrix
/// cache keeps it.
fn eye_tag(eye: Vec3) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    eye.to_array().map(f32::to_bits).hash(&mut h);
    h.finish()
}

/// A stacked view of an EM layer, as its solve reads it.
struct NeighbourView {
    tag: u64,
    /// Its rows' weight in the solve.
    weight: f32,
    geometry: ProbeGeometry,
    pixels: Vec<[f32; 4]>,
    /// Per pixel, with `[objects.em] display_weight`.
    pixel_weights: Option<Vec<f32>>,
}

/// The neighbours' views of `job` as the solve stacks them: each with the
/// sample's target but its own traced pixels, at its weight.
fn stacked_views<'a>(
    job: &Job,
    neighbours: &'a [NeighbourView],
    target: Target<'a>,
) -> Vec<View<'a>> {
    neighbours
        .iter()
        .map(|n| View {
            id: view_id(job, n.tag),
            geometry: &n.geometry,
            target: Target {
                pixels: &n.pixels,
                ..target
            },
            weight: n.weight,
            pixel_weights: n.pixel_weights.as_deref(),
        })
        .collect()
}

/// The cache id of `job`'s rendering matrix at view `tag`: within one run
/// a job and a view fix the probe geometry and texture layout.
fn view_id(job: &Job, tag: u64) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    job.name().hash(&mut h);
    tag.hash(&mut h);
    h.finish()
}

/// The traced pixels `job`'s map must reproduce: its own layer (the local
/// one premultiplied), the whole specular appearance for the sphere EM, or
/// the composite for the PTM.
fn job_target_pixels(
    job: &Job,
    layers: &[output::ExrLayer],
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>> {
    Ok(match job.layer {
        MapLayer::Distant | MapLayer::Local => target_pixels(
            layers,
            &job.name(),
            job.layer == MapLayer::Local,
            pixel_count,
        )?,
        MapLayer::Sphere => specular_pixels(layers, &job.object.name, pixel_count)?,
        MapLayer::Ptm => composite_pixels(layers, &job.object.name, pixel_count)?,
    })
}

/// The progress bar's message while sample `k`'s stacked views are found.
fn stack_message(k: u32, stack: &Stack) -> String {
    let ring = match stack.deg {
        Some(d) => format!("views ±{d}°"),
        None => "neighbouring samples' views".to_string(),
    };
    match stack.above_deg.as_slice() {
        [] => format!("sample {k}: {ring} (traced when missing)"),
        above => format!("sample {k}: {ring} and {above:?}° above (traced when missing)"),
    }
}

/// One printed line per map inferred.
fn layer_line(sample: u32, l: &LayerReport) -> String {
    format!(
        "sample {:>3} {:<26} LS {:>6.2} dB  forward {:>6.2} dB{}  A·x vs render {:>6.1} dB  {} rows  {} renders  probe {:.1} s  assembly {:.1} s  solve {:.2} s ({:?} CG it.)\n",
        sample,
        l.name,
        l.psnr_db.least_squares,
        l.psnr_db.forward_mapping,
        l.psnr_db
            .static_em
            .map_or(String::new(), |v| format!("  static EM {v:>6.2} dB")),
        l.a_vs_render_psnr_db,
        l.rows,
        l.probe_renders,
        l.probe_s,
        l.assembly_s,
        l.solve_s,
        l.cg_iterations
    )
}

/// Per-vertex cube lookups of `mesh` seen from `eye` for an EM on
/// `geometry` centred at `origin` (CPU texgen), read with `lod_bias`.
fn cube_lookup(
    geometry: &EmGeometry,
    origin: Vec3,
    eye: Vec3,
    mesh: &Mesh,
    lod_bias: f32,
) -> Lookup {
    let mut lookups = vec![[0.0f32; 4]; mesh.positions.len()];
    texgen(
        geometry,
        origin,
        eye,
        &mesh.positions,
        &mesh.normals,
        &mut lookups,
    );
    Lookup::Cube {
        dirs: lookups
            .iter()
            .map(|l| Vec3::new(l[0], l[1], l[2]))
            .collect(),
        lod_bias,
    }
}
