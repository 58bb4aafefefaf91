//! `engine infer`: layered environment maps by least squares for orbit
//! samples. Per sample: the traced layers (traced first when missing or
//! stale), then for each reflector with `[objects.em]` and each of its
//! layers — distant on the room's box, local on the reflector's
//! minimum-volume ellipsoid (premultiplied RGBA), with `--sphere` one
//! sphere-at-infinity EM for its whole specular appearance — and its PTM:
//! probe renders on this device, the regularized solve warm-started from the
//! previous sample, the forward-mapping baseline, and the maps written as
//! EXR with a report. With `--all`, maps whose inputs are unchanged are
//! skipped and their entries in the sample's report kept.

mod baselines;
mod diffuse;
mod jobs;
mod pictures;
mod report;
mod summary;
pub(crate) mod targets;

use crate::backend::{DeviceOptions, create_device};
use crate::cli::InferArgs;
use crate::play::prepare_output;
use crate::probe::VulkanProbe;
use anyhow::{Context, Result, bail};
use glam::Vec3;
use inference::em_geometry::{EmGeometry, texgen};
use inference::infer::maps::{read_map, write_map};
use inference::infer::{Target, infer_layer};
use inference::probe::{Lookup, ProbeGeometry};
use inference::scene::{EmLayer, Mesh, Scene};
use inference::solve::SolveOptions;
use inference::solve::layout::TextureLayout;
use inference::trace::{TraceSettings, Tracer, cache, camera};
use std::path::{Path, PathBuf};

use baselines::{static_em_psnr, static_ems};
use diffuse::infer_diffuse;
use jobs::{Kind, inputs_key, jobs_for};
use pictures::{write_comparison, write_map_picture};
use report::{LayerReport, SampleReport, finite_or_max};
use targets::{composite_pixels, specular_pixels, target_pixels, traced_layers};

pub(super) fn output_dir(args: &InferArgs, scene: &Scene) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("infer"))
}

/// How targets are traced when missing: the size of the probe renders.
pub(super) fn trace_settings(args: &InferArgs) -> Result<TraceSettings> {
    let (width, height) = args.size;
    let settings = TraceSettings {
        width,
        height,
        spp: args.spp.unwrap_or(inference::trace::DEFAULT_SPP),
        progress: true,
        ..TraceSettings::default()
    };
    settings.validate()?;
    Ok(settings)
}

/// Where traced targets live: `--trace-dir`, else `out/<scene>/trace`.
pub(super) fn trace_dir(args: &InferArgs, scene: &Scene) -> PathBuf {
    args.trace_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("trace"))
}

pub(super) fn open_device(args: &InferArgs) -> Result<crate::backend::Device> {
    Ok(create_device(&DeviceOptions {
        device_name: args.device.clone(),
        validate: args.validate,
    })?)
}

pub fn infer(args: &InferArgs) -> Result<String> {
    if let Some(object) = &args.diffuse {
        return infer_diffuse(args, object);
    }
    let scene = Scene::load(&args.scene)?;
    let tracer = Tracer::new(&scene)?;
    let (width, height) = args.size;
    let settings = trace_settings(args)?;
    let samples: Vec<u32> = match args.sample {
        Some(k) if k >= scene.orbit.samples => {
            bail!(
                "--sample {k}: out of range 0..{} (the scene's orbit.samples)",
                scene.orbit.samples
            )
        }
        Some(k) => vec![k],
        None => (0..scene.orbit.samples).collect(),
    };
    let jobs = jobs_for(&scene, args.em_size, args.sphere)?;
    if jobs.is_empty() {
        bail!(
            "{}: no reflective object has [objects.em] settings: nothing to infer",
            scene.source.display()
        );
    }
    let out = output_dir(args, &scene);
    prepare_output(&out)?;
    let trace_dir = trace_dir(args, &scene);
    let options = SolveOptions {
        eps_f: args.eps_f,
        ..SolveOptions::default()
    };
    if args.all {
        // Before any work: which maps will be skipped, so a changed key
        // shows at once rather than after hours of re-inference.
        let mut line = String::from("up to date, skipped / to infer:");
        for job in &jobs {
            let mut fresh = 0;
            for &k in &samples {
                let trace_key = cache::key(&scene, tracer.sample_eye(k)?, &settings);
                let key = inputs_key(trace_key, job, &options, args.size);
                fresh += usize::from(up_to_date(&out, k, &job.name(), key));
            }
            line += &format!(" {} {fresh}/{}", job.name(), samples.len() - fresh);
        }
        eprintln!("{line}");
    }
    let device = open_device(args)?;
    let mut probe = VulkanProbe::new(&device)?;
    let projection = camera::projection(&scene, width, height);
    let pixel_count = width as usize * height as usize;
    let static_ems = static_ems(&device, &scene, width, height)?;
    let bar = indicatif::ProgressBar::new(samples.len() as u64 * jobs.len() as u64);
    let order: Vec<String> = jobs.iter().map(|j| j.name()).collect();
    let mut reports = Vec::new();
    let mut text = String::new();
    let mut skipped = 0;
    for &k in &samples {
        let (layers, trace_key) = traced_layers(&trace_dir, &scene, &tracer, k, &settings)?;
        let eye = tracer.sample_eye(k)?;
        let dir = out.join(format!("sample_{k:04}"));
        prepare_output(&dir)?;
        let report_path = dir.join("report.json");
        // The sample's earlier report, read before the first map inferred.
        let mut old_report = None;
        let mut fresh = Vec::new();
        let mut warm_started = false;
        for job in &jobs {
            let name = job.name();
            let key = inputs_key(trace_key, job, &options, args.size);
            let key_path = dir.join(format!("{name}.key"));
            let map_path = dir.join(format!("{name}.exr"));
            if args.all && up_to_date(&out, k, &name, key) {
                skipped += 1;
                bar.inc(1);
                continue;
            }
            if old_report.is_none() {
                old_report = Some(SampleReport::read(&report_path, k)?);
            }
            let mesh = &job.object.mesh;
            let (pixels, lookup) = match job.kind {
                Kind::Em(layer, em_geometry) => (
                    target_pixels(&layers, &name, layer == EmLayer::Local, pixel_count)?,
                    cube_lookup(&em_geometry, job.origin, eye, mesh),
                ),
                Kind::Whole(em_geometry) => (
                    specular_pixels(&layers, &job.object.name, pixel_count)?,
                    cube_lookup(&em_geometry, job.origin, eye, mesh),
                ),
                Kind::Ptm => (
                    composite_pixels(&layers, &job.object.name, pixel_count)?,
                    Lookup::Uv(mesh.uvs.clone()),
                ),
            };
            let geometry = ProbeGeometry {
                key: key ^ u64::from(k),
                positions: mesh.positions.clone(),
                indices: mesh.indices.clone(),
                lookup,
                view_proj: projection * scene.orbit.view(eye),
                width,
                height,
            };
            let shape = job.shape();
            let layout = TextureLayout::full_chain(shape);
            let previous = k
                .checked_sub(1)
                .map(|p| {
                    out.join(format!("sample_{p:04}"))
                        .join(format!("{name}.exr"))
                })
                .filter(|p| p.is_file())
                .and_then(|p| read_map(&p, &layout, job.channels()).ok());
            warm_started |= previous.is_some();
            bar.set_message(format!("sample {k} {name}"));
            let target = Target {
                name: &name,
                pixels: &pixels,
                channels: job.channels(),
            };
            let result = infer_layer(
                &mut probe,
                &geometry,
                shape,
                &target,
                previous.as_deref(),
                &options,
                &mut |_, _| {},
            )
            .with_context(|| {
                let file = trace_dir.join(format!("sample_{k:04}.exr"));
                format!("{}: sample {k}, {name}", file.display())
            })?;
            write_map(&map_path, &layout, &result.map)?;
            write_comparison(&dir.join(format!("{name}.png")), width, &pixels, &result)?;
            write_map_picture(&dir.join(format!("{name}.map.png")), &layout, &result.map)?;
            std::fs::write(&key_path, key.to_string())
                .with_context(|| format!("writing {}", key_path.display()))?;
            let mut layer_report = LayerReport::from(&result);
            // The static EM against the targets it stands for: the distant
            // layer and the whole specular appearance.
            if let (Kind::Em(EmLayer::Distant, _) | Kind::Whole(_), Some(em)) =
                (job.kind, static_ems.get(&job.object.name))
            {
                let target = Target {
                    name: &name,
                    pixels: &pixels,
                    channels: 3,
                };
                let psnr = static_em_psnr(
                    &mut probe,
                    &geometry,
                    mesh,
                    em,
                    eye,
                    &target,
                    &result.pixels,
                )?;
                layer_report.psnr_db.static_em = Some(finite_or_max(psnr));
            }
            text += &layer_line(k, &layer_report);
            fresh.push(layer_report);
            bar.inc(1);
        }
        if !fresh.is_empty() {
            let report = SampleReport::merged(old_report.flatten(), k, fresh, warm_started, &order);
            std::fs::write(&report_path, serde_json::to_string_pretty(&report)?)
                .with_context(|| format!("writing {}", report_path.display()))?;
            reports.push(report);
        }
    }
    bar.finish_and_clear();
    if skipped > 0 {
        text += &format!("{skipped} layers already inferred from the same inputs: skipped\n");
    }
    if args.all {
        text += &summary::summarize(&out)?;
    }
    // A single sample's report is also DIR/report.json, as tools expect.
    if let [only] = reports.as_slice() {
        std::fs::write(out.join("report.json"), serde_json::to_string_pretty(only)?)?;
    } else if !reports.is_empty() {
        std::fs::write(
            out.join("report.json"),
            serde_json::to_string_pretty(&reports)?,
        )?;
    }
    Ok(text)
}

/// Whether sample `k`'s map `name` under `out` exists and was inferred from
/// inputs with `key`.
fn up_to_date(out: &Path, k: u32, name: &str, key: u64) -> bool {
    let dir = out.join(format!("sample_{k:04}"));
    dir.join(format!("{name}.exr")).is_file()
        && std::fs::read_to_string(dir.join(format!("{name}.key"))).ok() == Some(key.to_string())
}

/// One printed line per layer inferred.
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
/// `geometry` centred at `origin` (CPU texgen).
fn cube_lookup(geometry: &EmGeometry, origin: Vec3, eye: Vec3, mesh: &Mesh) -> Lookup {
    let mut lookups = vec![[0.0f32; 4]; mesh.positions.len()];
    texgen(
        geometry,
        origin,
        eye,
        &mesh.positions,
        &mesh.normals,
        &mut lookups,
    );
    Lookup::Cube(
        lookups
            .iter()
            .map(|l| Vec3::new(l[0], l[1], l[2]))
            .collect(),
    )
}
