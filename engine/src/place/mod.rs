//! `engine place`: how many viewpoint samples a scene needs, and where:
//! the azimuth lines of a 1D orbit, or (`--rings`) the elevation rings of
//! a 2D one, each ring with every azimuth line.
//! On a dense compile (every line inferred), each candidate interval is
//! scored by playing a held-out view near its middle ([`probe_azimuth`])
//! blended from its two ends only, against the traced view there;
//! [`plan::place`] splits the worst until every interval reaches the
//! target or the budget is spent. The same measurement scores an even
//! placement with as many samples, so the report compares the two on
//! equal terms.

mod axis;
mod budget;
pub mod plan;
mod report;

pub use axis::Axis;
pub use budget::{Budget, Cost};
pub use plan::{Interval, Plan, PlanOptions, Stop};
pub use report::PlaceReport;

use crate::eval::metrics;
use crate::eval::reference::{References, View};
use crate::options::{Mode, PemOptions, RunPlace};
use crate::play::{FrameSource, Session, compile_context, setup_mode};
use crate::renderer::Renderer;
use anyhow::{Context, Result, bail};
use inference::scene::Scene;
use inference::trace::TraceSettings;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// What to place and how to measure it.
#[derive(Clone, Debug)]
pub struct PlaceOptions {
    /// Where placement.json, placement.png and the references go
    /// [default: `<data>/place`].
    pub out: Option<PathBuf>,
    pub target_db: f64,
    pub max_samples: u32,
    /// At most this many container bytes, estimated from the dense
    /// container's bytes per sample ([`plan::samples_within_bytes`]).
    pub max_bytes: Option<u64>,
    /// At most this many minutes of compile, estimated from the dense
    /// compile's recorded minutes per sample.
    pub max_minutes: Option<f64>,
    pub start: u32,
    /// Samples per pixel of the traced views.
    pub spp: u32,
    /// Which lines to place.
    pub axis: Axis,
}

/// Places the samples of `place`'s scene (compiled there densely first if
/// missing); writes the report and chart; returns the printed summary.
pub fn place(place: &RunPlace, opts: &PlaceOptions) -> Result<String> {
    let Session {
        scene,
        out: data,
        mut renderer,
        ..
    } = Session::open(place)?;
    opts.axis.check(&scene)?;
    let per_line = opts.axis.samples_per_line(&scene.orbit);
    let mut plan_opts = PlanOptions {
        lines: opts.axis.lines(&scene.orbit),
        start: opts.start,
        max_samples: opts.max_samples / per_line,
        target_db: opts.target_db,
    };
    let noun = opts.axis.noun();
    plan_opts.validate().with_context(|| match opts.axis {
        Axis::Azimuth => format!("{}: [orbit]", scene.source.display()),
        Axis::Rings => format!(
            "{}: --rings: a ring is {per_line} samples, so --max-samples {} buys {} rings",
            scene.source.display(),
            opts.max_samples,
            plan_opts.max_samples
        ),
    })?;
    if plan_opts.start >= plan_opts.lines {
        bail!(
            "{}: --start {} places all {} dense {noun}: nothing is left to choose (expected \
             --start below {}, e.g. 2)",
            scene.source.display(),
            plan_opts.start,
            plan_opts.lines,
            plan_opts.lines
        );
    }
    let out = opts.out.clone().unwrap_or_else(|| data.join("place"));
    crate::util::files::claim_dir(&out)?;
    let reflector = crate::eval::reflector_name(&scene)?;
    let ctx = compile_context(place, &scene, &data);
    let mut source = setup_mode(
        &ctx,
        &mut renderer,
        Mode::LayeredPem,
        &PemOptions::default(),
        1,
    )?;
    let settings = TraceSettings {
        width: place.size.0,
        height: place.size.1,
        spp: opts.spp,
        progress: false,
        ..TraceSettings::default()
    };
    let bytes = Budget::of(
        Cost::Bytes,
        opts.max_bytes.map(|b| b as f64),
        &renderer,
        &scene,
    )?;
    let minutes = Budget::of(Cost::Minutes, opts.max_minutes, &renderer, &scene)?;
    for b in bytes.iter().chain(&minutes) {
        b.limit(&mut plan_opts, per_line)?;
    }
    let references = References::new(&scene, &out.join("reference"), settings)?;
    let progress = spinner();
    let start = Instant::now();
    let mut probe = Probe {
        scene: &scene,
        renderer: &mut renderer,
        source: &mut source,
        references: &references,
        reflector: &reflector,
    };
    let mut seen = BTreeMap::new();
    let mut measure = |from, to, at| {
        progress.set_message(format!("{noun} {from}..{to}: views past {at}"));
        let db = match opts.axis {
            Axis::Azimuth => probe.score(from, to, at),
            Axis::Rings => probe.score_rings(from, to, at),
        };
        progress.inc(1);
        db
    };
    let plan = plan::place(&plan_opts, &mut seen, &mut measure)?;
    let even_lines = plan::uniform(plan_opts.lines, plan.lines.len() as u32);
    let even = plan::measure_intervals(&even_lines, &mut seen, &mut measure)?;
    progress.finish_and_clear();
    let budgets = [bytes, minutes];
    let report = PlaceReport::new(
        &scene,
        opts,
        budgets,
        plan,
        even_lines,
        even,
        start.elapsed(),
    );
    report.write(&out)?;
    let scene_file = placed_scene(&place.scene, &scene, &report, &out);
    Ok(report.summary(&out) + &scene_file)
}

/// Writes `<name>_placed.toml` under `out`: the scene with the placed
/// lines, checked to load from there; returns what to print (how to
/// play it, or why it could not be written and the line to copy).
///
/// The scores were measured on maps whose solves stacked the dense lines'
/// neighbours; a placed sample's neighbours lie further off, so objects
/// that stack neighbouring samples stack views at the dense spacing
/// instead, as the maps that were scored did.
fn placed_scene(
    scene_arg: &str,
    dense: &Scene,
    report: &PlaceReport,
    out: &std::path::Path,
) -> String {
    use inference::scene::placed::{with_azimuths, with_neighbour_deg, with_rings};
    type Rewrite = fn(&str, &str, &[f32], &str) -> Option<String>;
    let (key, lines, rewrite): (_, _, Rewrite) = match report.axis {
        Axis::Azimuth => ("azimuths_deg", &report.placed.azimuths_deg, with_azimuths),
        Axis::Rings => (
            "ring_elevations_deg",
            &report.placed.elevations_deg,
            with_rings,
        ),
    };
    let name = format!("{}_placed", report.scene);
    let path = out.join(format!("{name}.toml"));
    let note = format!("placed by `engine place`: {}", report.reason);
    // (Stacked neighbours are azimuth neighbours, which placing rings keeps.)
    let stacks_samples = report.axis == Axis::Azimuth
        && dense
            .objects
            .iter()
            .any(|o| o.neighbour_weight() > 0.0 && o.neighbour_deg().is_none());
    let written = (|| -> Result<()> {
        let (text, _) = Scene::text(scene_arg)?;
        let Some(mut text) = rewrite(&text, &name, lines, &note) else {
            bail!("the scene file has no [orbit] table or no top-level name line to rewrite");
        };
        if stacks_samples {
            let spacing = dense.orbit.step_deg;
            let why = format!("as the scored maps did: the {} lines' spacing", dense.name);
            text = with_neighbour_deg(&text, spacing, &why);
        }
        Scene::from_toml(&text, &path)?;
        crate::util::files::write(&path, text.as_bytes())
    })();
    match written {
        Ok(()) => format!(
            "wrote {0}; play it with `engine --scene {0}`\n",
            path.display()
        ),
        Err(e) => format!(
            "no placed scene file ({e:#}); put `{key} = {lines:?}` in [orbit] instead of its \
             even {}\n",
            report.axis.noun()
        ),
    }
}

fn spinner() -> indicatif::ProgressBar {
    indicatif::ProgressBar::new_spinner().with_style(
        indicatif::ProgressStyle::with_template(
            "place {spinner} {pos} views scored, {msg} {elapsed}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    )
}

/// The azimuth of the view that scores the interval split at line
/// `at`: half a line past it — the interval's middle when its lines are
/// an odd number apart — so no dense solve saw it. The line itself is a
/// view the dense solves of its neighbours stacked (`neighbour_weight`),
/// and a blend fitted there scored 3–5 dB above the views between lines
/// that `engine eval` and users see.
pub fn probe_azimuth(orbit: &inference::scene::Orbit, at: u32) -> f32 {
    orbit.between_deg(at, 0.5)
}

/// Scores one view blended from two lines.
struct Probe<'a, 's> {
    scene: &'a Scene,
    renderer: &'a mut Renderer,
    source: &'a mut FrameSource<'s>,
    references: &'a References<'a>,
    reflector: &'a str,
}

impl Probe<'_, '_> {
    /// Reflector PSNR (as `engine eval` scores it) of the frame at
    /// [`probe_azimuth`]`(at)` blended from lines `from` and `to` alone.
    fn score(&mut self, from: u32, to: u32, at: u32) -> Result<f64> {
        let view = View::on_orbit(probe_azimuth(&self.scene.orbit, at));
        self.renderer.use_azimuth_lines(Some(&[from, to]));
        let db = self.score_view(view);
        self.renderer.use_azimuth_lines(None);
        db
    }

    /// The lowest reflector PSNR of the views half way between rings `at`
    /// and `at + 1`, one on each azimuth line (so only the rings blend),
    /// blended from rings `from` and `to` alone: "every interval reaches
    /// the target" then holds for every view scored.
    fn score_rings(&mut self, from: u32, to: u32, at: u32) -> Result<f64> {
        let scene = self.scene;
        let elevation = Axis::Rings.probe_deg(&scene.orbit, at);
        self.renderer.use_rings(Some(&[from, to]));
        let scores: Result<Vec<f64>> = (0..scene.orbit.samples)
            .map(|line| self.score_view(View::new(scene.orbit.angle_deg(line), elevation)))
            .collect();
        self.renderer.use_rings(None);
        Ok(scores?.into_iter().fold(f64::INFINITY, f64::min))
    }

    /// Reflector PSNR of the frame at `view` with the blend as set.
    fn score_view(&mut self, view: View) -> Result<f64> {
        let reference = self.references.get(view, self.reflector)?;
        let eye = view.eye(self.scene);
        // The first frame brings the samples' maps in; the second is scored.
        self.source.frame(self.renderer, self.scene, eye)?;
        self.renderer.settle();
        let pixels = self.source.frame(self.renderer, self.scene, eye)?.1;
        let (width, height) = self.renderer.size();
        match metrics::masked_psnr(&reference.beauty, &pixels, &reference.mask)? {
            Some(db) => Ok(db),
            None => bail!(
                "view at azimuth {}°, elevation {}°: {} covers no pixel at {width}x{height}",
                view.azimuth_deg,
                view.elevation_deg,
                self.reflector
            ),
        }
    }
}
