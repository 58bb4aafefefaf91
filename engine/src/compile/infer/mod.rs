//! Inference of every reflector's maps for orbit samples. Per sample: the
//! traced layers (traced first when missing, stale or damaged), then for
//! each map the scene asks for ([`jobs_for`]) — distant on the room's box,
//! local on the reflector's minimum-volume ellipsoid (premultiplied RGBA),
//! on request one sphere-at-infinity EM for the whole specular appearance,
//! and the PTM — probe renders on this device, the regularized solve
//! warm-started from the previous sample, the forward-mapping baseline, and
//! the map written as EXR with its key record, and the sample's report
//! merged after every map (an interrupted run loses no finished map).

mod baselines;
mod budget;
mod diffuse;
mod display_weights;
mod jobs;
mod pictures;
mod report;
mod sample;
mod summary;
pub mod targets;

pub use budget::{Budget, inputs_budget};
pub use diffuse::{DiffuseRequest, infer_diffuse};
pub use jobs::{INFERENCE_VERSION, Job, jobs_for, map_key};
use jobs::{keyed_map, map_settings, missing_neighbours};
pub use sample::WARM_CHAIN;

use crate::backend::{DeviceOptions, create_device};
use crate::maps::{MapLayer, map_path};
use crate::util::files::claim_dir;
use anyhow::{Result, bail};
use inference::key::{Freshness, Key};
use inference::scene::Scene;
use inference::solve::SolveOptions;
use inference::trace::{TraceSettings, Tracer, cache};
use std::path::PathBuf;

/// What to infer and where.
#[derive(Clone, Debug)]
pub struct InferRequest {
    /// Orbit samples to infer.
    pub samples: Vec<u32>,
    /// Keep maps already inferred from the same inputs (`--all`).
    pub skip_fresh: bool,
    /// Also the sphere-at-infinity EM of every reflector.
    pub sphere: bool,
    /// Cube-map size for every EM [default: the scene's].
    pub em_size: Option<u32>,
    /// Size of the targets and probe renders.
    pub size: (u32, u32),
    /// Samples per pixel when a target must be traced.
    pub spp: u32,
    /// Pyramidal regularization weight ε_f.
    pub eps_f: f32,
    /// Where traced targets are read from (and traced into when missing).
    pub trace_dir: PathBuf,
    /// Where the maps go.
    pub infer_dir: PathBuf,
    pub device: DeviceOptions,
}

impl InferRequest {
    /// Every sample of `scene`, skipping fresh maps, with the defaults.
    pub fn all(scene: &Scene, trace_dir: PathBuf, infer_dir: PathBuf) -> Self {
        Self {
            samples: (0..scene.orbit.sample_count()).collect(),
            skip_fresh: true,
            sphere: false,
            em_size: None,
            size: (640, 480),
            spp: inference::trace::DEFAULT_SPP,
            eps_f: 0.1,
            trace_dir,
            infer_dir,
            device: DeviceOptions::default(),
        }
    }

    pub fn trace_settings(&self) -> Result<TraceSettings> {
        let settings = TraceSettings {
            width: self.size.0,
            height: self.size.1,
            spp: self.spp,
            progress: true,
            ..TraceSettings::default()
        };
        settings.validate()?;
        Ok(settings)
    }

    pub fn solve_options(&self) -> SolveOptions {
        SolveOptions {
            eps_f: self.eps_f,
            ..SolveOptions::default()
        }
    }
}

/// Weight of the local layer's prior toward transparent.
pub const LOCAL_PRIOR: f32 = 0.01;

/// What is known before any work: the scene's maps and the key each map
/// of each sample must carry.
pub struct Plan<'a> {
    pub scene: &'a Scene,
    pub jobs: Vec<Job<'a>>,
    /// Per job, the hash of its maps' own inputs ([`map_settings`]).
    job_settings: Vec<u64>,
    pub scene_key: Key,
    pub settings: TraceSettings,
    pub options: SolveOptions,
}

impl<'a> Plan<'a> {
    pub fn new(scene: &'a Scene, req: &InferRequest) -> Result<Self> {
        if let Some(&k) = req
            .samples
            .iter()
            .find(|&&k| k >= scene.orbit.sample_count())
        {
            bail!(
                "--sample {k}: out of range 0..{} (orbit.samples × orbit.rings)",
                scene.orbit.sample_count()
            );
        }
        let jobs = jobs_for(scene, req.em_size, req.sphere)?;
        if jobs.is_empty() {
            bail!(
                "{}: no reflective object has [objects.em] settings: nothing to infer",
                scene.origin
            );
        }
        let mut plan = Self {
            scene,
            jobs,
            job_settings: Vec::new(),
            scene_key: cache::scene_key(scene),
            settings: req.trace_settings()?,
            options: req.solve_options(),
        };
        let size = (plan.settings.width, plan.settings.height);
        plan.job_settings = (plan.jobs.iter())
            .map(|job| map_settings(job, &plan.options_for(job), size))
            .collect();
        Ok(plan)
    }

    /// The traced target's key of sample `k`.
    pub fn trace_key(&self, k: u32) -> Result<Key> {
        let eye = self.scene.orbit.sample_eye(k)?;
        Ok(cache::image_key(&self.scene_key, eye, &self.settings))
    }

    /// The key sample `k`'s map of `job` must carry (`trace_key` is
    /// sample `k`'s).
    pub fn key(&self, k: u32, trace_key: &Key, job: &Job) -> Key {
        let size = (self.settings.width, self.settings.height);
        let settings = (self.jobs.iter().zip(&self.job_settings))
            .find(|(j, _)| std::ptr::eq(*j, job))
            .map(|(_, &h)| h)
            .unwrap_or_else(|| map_settings(job, &self.options_for(job), size));
        let key = keyed_map(trace_key, settings);
        // The neighbours' traces are inputs too. Their eyes follow from
        // this sample's (placed lines are all in every trace key), but not
        // whether the arc ends beside it: a 1D orbit's trace keys leave out
        // the sample count. Offset views follow from the sample's eye and
        // the offset, which the map key holds.
        let place = self.scene.orbit.ring_position(k);
        let stacks_samples = job.neighbour_weight() > 0.0 && job.neighbour_deg().is_none();
        match (stacks_samples, missing_neighbours(place)) {
            (true, missing) if missing != 0 => key.with("neighbours missing", missing),
            _ => key,
        }
    }

    /// The solve options of `job`: local layers add a prior toward
    /// transparent, so texels only off-sample views reach stay see-through
    /// rather than smearing what the sample's view saw (measured in the
    /// README, "Off the orbit"), and only they (premultiplied RGBA) take
    /// the object's bounds (`[objects.em] local_bound`).
    pub fn options_for(&self, job: &Job) -> SolveOptions {
        let local = job.layer == MapLayer::Local;
        SolveOptions {
            eps_prior: if local { LOCAL_PRIOR } else { 0.0 },
            eps_bound: if local { job.object.local_bound() } else { 0.0 },
            ..self.options.clone()
        }
    }

    /// Every (sample, job index) of `samples` whose map is not fresh, with
    /// what is wrong with it.
    pub fn stale(
        &self,
        samples: &[u32],
        infer_dir: &std::path::Path,
    ) -> Result<Vec<(u32, usize, Freshness)>> {
        let mut stale = Vec::new();
        for &k in samples {
            let trace_key = self.trace_key(k)?;
            for (i, job) in self.jobs.iter().enumerate() {
                let path = map_path(infer_dir, k, &job.object.name, job.layer);
                let f = inference::key::freshness(&path, &self.key(k, &trace_key, job));
                if f != Freshness::Fresh {
                    stale.push((k, i, f));
                }
            }
        }
        Ok(stale)
    }
}

/// Infers what `req` asks for; returns the printed lines (per map, and
/// with `skip_fresh` the medians over every sample inferred so far).
pub fn infer(scene: &Scene, req: &InferRequest) -> Result<String> {
    let plan = Plan::new(scene, req)?;
    claim_dir(&req.infer_dir)?;
    let todo: Vec<(u32, Vec<usize>)> = if req.skip_fresh {
        // Before any work: what will be skipped, so a changed key shows at
        // once rather than after hours of re-inference.
        let stale = plan.stale(&req.samples, &req.infer_dir)?;
        eprintln!("{}", stale_line(&plan, &stale, req.samples.len()));
        group_by_sample(&stale)
    } else {
        let all: Vec<usize> = (0..plan.jobs.len()).collect();
        req.samples.iter().map(|&k| (k, all.clone())).collect()
    };
    let skipped =
        req.samples.len() * plan.jobs.len() - todo.iter().map(|t| t.1.len()).sum::<usize>();
    let device = create_device(&req.device)?;
    let mut run = sample::SampleRun::new(&plan, req, &device, Tracer::new(scene)?)?;
    let bar = indicatif::ProgressBar::new(todo.iter().map(|t| t.1.len() as u64).sum()).with_style(
        indicatif::ProgressStyle::with_template(
            "infer [{bar:30}] {pos}/{len} maps {elapsed}, about {eta} left: {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut text = String::new();
    let mut reports = Vec::new();
    for (k, jobs) in &todo {
        let (report, lines) = run.infer_sample(*k, jobs, &bar)?;
        text += &lines;
        reports.push(report);
    }
    bar.finish_and_clear();
    if skipped > 0 {
        text += &format!("{skipped} maps already inferred from the same inputs: skipped\n");
    }
    if req.skip_fresh {
        text += &summary::summarize(&req.infer_dir)?;
    }
    // A single sample's report is also DIR/report.json, as tools expect.
    let top = req.infer_dir.join("report.json");
    match reports.as_slice() {
        [] => {}
        [only] => crate::util::files::write_json(&top, only)?,
        all => crate::util::files::write_json(&top, &all)?,
    }
    Ok(text)
}

/// `fresh / to infer` per map kind, and the first reasons.
fn stale_line(plan: &Plan, stale: &[(u32, usize, Freshness)], samples: usize) -> String {
    let mut line = String::from("up to date / to infer:");
    for (i, job) in plan.jobs.iter().enumerate() {
        let n = stale.iter().filter(|s| s.1 == i).count();
        line += &format!(" {} {}/{n}", job.name(), samples - n);
    }
    let reasons: Vec<String> = stale
        .iter()
        .filter_map(|(k, i, f)| match f {
            Freshness::Stale(what) => Some(format!(
                "sample {k} {}: {} changed",
                plan.jobs[*i].name(),
                what.join(", ")
            )),
            Freshness::Broken(why) => Some(format!("{why}: inferring it again")),
            _ => None,
        })
        .take(3)
        .collect();
    if !reasons.is_empty() {
        line += &format!(
            " ({}{})",
            reasons.join("; "),
            if stale.len() > 3 { "; …" } else { "" }
        );
    }
    line
}

fn group_by_sample(stale: &[(u32, usize, Freshness)]) -> Vec<(u32, Vec<usize>)> {
    let mut out: Vec<(u32, Vec<usize>)> = Vec::new();
    for &(k, i, _) in stale {
        match out.last_mut() {
            Some((last, jobs)) if *last == k => jobs.push(i),
            _ => out.push((k, vec![i])),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{InferRequest, Plan};
    use inference::scene::Scene;

    /// The built-in teapot (neighbour_weight = 1) with `samples` samples.
    fn scene(samples: &str) -> Scene {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("t.toml");
        let text = inference::scene::shipped::shipped("teapot").expect("teapot.toml");
        let text = inference::scene::shipped::without_views_above(text);
        std::fs::write(&path, text.replacen("samples = 100", samples, 1)).expect("write");
        Scene::load(&path.to_string_lossy()).expect("scene loads")
    }

    fn request() -> InferRequest {
        InferRequest {
            samples: vec![],
            skip_fresh: true,
            sphere: false,
            em_size: None,
            size: (64, 48),
            spp: 1,
            eps_f: 0.0,
            trace_dir: "t".into(),
            infer_dir: "i".into(),
            device: Default::default(),
        }
    }

    #[test]
    fn a_sample_whose_neighbour_the_arc_now_cuts_off_is_stale() {
        let request = request();
        let (long, short) = (scene("samples = 100"), scene("samples = 3"));
        let (long, short) = (
            Plan::new(&long, &request).expect("plan"),
            Plan::new(&short, &request).expect("plan"),
        );
        for job in 0..long.jobs.len() {
            let key = |plan: &Plan, k: u32| {
                let trace = plan.trace_key(k).expect("trace key");
                plan.key(k, &trace, &plan.jobs[job]).hash()
            };
            // The traces' keys are equal (a 1D orbit's leave out the count).
            assert_eq!(long.trace_key(2).ok(), short.trace_key(2).ok());
            assert_eq!(key(&long, 1), key(&short, 1), "inside both arcs");
            let layered = long.jobs[job].neighbour_weight() > 0.0;
            assert_eq!(key(&long, 2) != key(&short, 2), layered, "sample 2");
        }
    }

    #[test]
    fn the_plan_hashes_each_jobs_settings_once_into_the_same_keys() {
        let (scene, request) = (scene("samples = 5"), request());
        let plan = Plan::new(&scene, &request).expect("plan");
        let size = (plan.settings.width, plan.settings.height);
        let trace = plan.trace_key(3).expect("trace key");
        let mut hashes = std::collections::HashSet::new();
        for job in &plan.jobs {
            let direct = super::map_key(&trace, job, &plan.options_for(job), size);
            assert_eq!(plan.key(3, &trace, job), direct, "{}", job.name());
            // A job that is not the plan's own (a copy) is hashed in full.
            let copy = super::Job {
                atlas: job.atlas.clone(),
                ..*job
            };
            assert_eq!(plan.key(3, &trace, &copy), direct, "{}", job.name());
            hashes.insert(direct.hash());
        }
        assert_eq!(
            hashes.len(),
            plan.jobs.len(),
            "every job keys its maps apart"
        );
    }

    /// The keys of sample `k`'s stacking maps on the teapot with
    /// `samples` and the `[objects.em]` lines `extra` (e.g. an offset:
    /// without one it stacks the neighbouring samples).
    fn stacking_keys(samples: &str, k: u32, extra: &str) -> Vec<u64> {
        let weight = "neighbour_weight = 1.0";
        let text = inference::scene::shipped::shipped("teapot").expect("teapot.toml");
        let text = inference::scene::shipped::without_views_above(text);
        let text = text.replacen("samples = 100", samples, 1).replacen(
            weight,
            &format!("{weight}\n{extra}"),
            1,
        );
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("t.toml");
        std::fs::write(&path, text).expect("write");
        let scene = Scene::load(&path.to_string_lossy()).expect("scene loads");
        let request = request();
        let plan = Plan::new(&scene, &request).expect("plan");
        let trace = plan.trace_key(k).expect("trace key");
        let jobs = plan.jobs.iter().filter(|j| j.neighbour_weight() > 0.0);
        jobs.map(|j| plan.key(k, &trace, j).hash()).collect()
    }

    #[test]
    fn offset_views_key_their_offset_and_not_where_the_arc_ends() {
        let ring = stacking_keys("samples = 3", 2, "");
        let (one, two) = (
            stacking_keys("samples = 3", 2, "neighbour_deg = 1.0"),
            stacking_keys("samples = 3", 2, "neighbour_deg = 2.0"),
        );
        assert!(!ring.is_empty() && ring.iter().zip(&one).all(|(r, o)| r != o));
        assert!(
            one.iter().zip(&two).all(|(a, b)| a != b),
            "the offset is keyed"
        );
        // Sample 2 ends a 3-line arc but not a 100-line one: its offset
        // views are the same either way, so is its key.
        assert_eq!(
            one,
            stacking_keys("samples = 100", 2, "neighbour_deg = 1.0")
        );
    }

    #[test]
    fn the_local_bound_keys_the_local_layer_only() {
        let free = stacking_keys("samples = 3", 1, "");
        let bounded = stacking_keys("samples = 3", 1, "local_bound = 10.0");
        let changed = free.iter().zip(&bounded).filter(|(f, b)| f != b).count();
        assert_eq!(changed, 1, "{free:?} vs {bounded:?}");
        let other = stacking_keys("samples = 3", 1, "local_bound = 1.0");
        assert_ne!(bounded, other, "the weight is keyed");
    }

    #[test]
    fn display_weights_key_every_map_they_weight() {
        let linear = stacking_keys("samples = 3", 1, "");
        let display = stacking_keys("samples = 3", 1, "display_weight = true");
        assert!(!linear.is_empty());
        assert!(
            linear.iter().zip(&display).all(|(l, d)| l != d),
            "{linear:?} vs {display:?}"
        );
        let off = stacking_keys("samples = 3", 1, "display_weight = false");
        assert_eq!(linear, off, "off keeps the keys maps had before");
    }

    #[test]
    fn views_above_key_their_elevations() {
        let keys = |above: &str| stacking_keys("samples = 3", 1, above);
        let none = keys("");
        let (a, b) = (
            keys("neighbour_above_deg = [15.0]"),
            keys("neighbour_above_deg = [15.0, 30.0]"),
        );
        assert!(!none.is_empty());
        for (x, y) in [(&none, &a), (&a, &b)] {
            assert!(x.iter().zip(y).all(|(p, q)| p != q), "{x:?} vs {y:?}");
        }
        assert_eq!(a, keys("neighbour_above_deg = [15.0]"), "deterministic");
        // Shared views above (a grid of azimuths) key their spacing.
        let shared = keys("neighbour_above_deg = [15.0]\nneighbour_above_spacing_deg = 4.0");
        assert!(
            a.iter().zip(&shared).all(|(p, q)| p != q),
            "{a:?} vs {shared:?}"
        );
        // Their own weight is keyed; unset they keep `neighbour_weight`'s keys.
        let light = keys("neighbour_above_deg = [15.0]\nneighbour_above_weight = 0.25");
        let full = keys("neighbour_above_deg = [15.0]\nneighbour_above_weight = 1.0");
        for other in [&light, &full] {
            assert!(a.iter().zip(other).all(|(p, q)| p != q), "{other:?}");
        }
        assert!(light.iter().zip(&full).all(|(p, q)| p != q));
    }
}
