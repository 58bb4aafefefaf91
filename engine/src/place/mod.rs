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
pub mod grid;
pub mod plan;
mod report;

pub use axis::{Axis, Placing};
pub use budget::{Budget, Cost};
pub use plan::{Interval, Plan, PlanOptions, Stop};
pub use report::PlaceReport;

use grid::GridOptions;
use report::Outcome;

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
    /// Lines placed evenly before measuring (per axis with the grid).
    pub start: u32,
    /// Samples per pixel of the traced views.
    pub spp: u32,
    /// Which lines to place.
    pub placing: Placing,
}

/// The refinement to run, its options checked against the scene.
enum Planned {
    Lines(Axis, PlanOptions),
    Grid(GridOptions),
}

impl Planned {
    /// Checks `opts` against `scene` before anything compiles.
    fn new(scene: &Scene, opts: &PlaceOptions) -> Result<Planned> {
        opts.placing.check(scene)?;
        let o = &scene.orbit;
        let Some(axis) = opts.placing.axis() else {
            let grid = GridOptions {
                lines: [o.samples, o.rings],
                start: [opts.start; 2],
                max_samples: opts.max_samples,
                target_db: opts.target_db,
            };
            grid.validate()
                .with_context(|| format!("{}: --grid", scene.origin))?;
            if grid.start_samples() >= o.sample_count() {
                bail!(
                    "{}: --start {} places all {} × {} dense lines × rings: nothing is left to \
                     choose (expected --start below one of them, e.g. 2)",
                    scene.origin,
                    opts.start,
                    o.samples,
                    o.rings
                );
            }
            return Ok(Planned::Grid(grid));
        };
        let per_line = axis.samples_per_line(o);
        let plan = PlanOptions {
            lines: axis.lines(o),
            start: opts.start,
            max_samples: opts.max_samples / per_line,
            target_db: opts.target_db,
        };
        plan.validate().with_context(|| match axis {
            Axis::Azimuth => format!("{}: [orbit]", scene.origin),
            Axis::Rings => format!(
                "{}: --rings: a ring is {per_line} samples, so --max-samples {} buys {} rings",
                scene.origin, opts.max_samples, plan.max_samples
            ),
        })?;
        if plan.start >= plan.lines {
            bail!(
                "{}: --start {} places all {} dense {}: nothing is left to choose (expected \
                 --start below {}, e.g. 2)",
                scene.origin,
                plan.start,
                plan.lines,
                axis.noun(),
                plan.lines
            );
        }
        Ok(Planned::Lines(axis, plan))
    }

    /// Caps the budget at what `budget` buys.
    fn limit(&mut self, budget: &Budget, orbit: &inference::scene::Orbit) -> Result<()> {
        match self {
            Planned::Lines(axis, plan) => budget.limit(plan, axis.samples_per_line(orbit)),
            Planned::Grid(grid) => budget.limit_grid(grid),
        }
    }
}

/// Places the samples of `place`'s scene (compiled there densely first if
/// missing); writes the report and chart; returns the printed summary.
pub fn place(place: &RunPlace, opts: &PlaceOptions) -> Result<String> {
    // Checked before the session claims a folder or compiles anything.
    let scene = inference::scene::Scene::load(&place.scene)?;
    check_dense(&scene)?;
    let mut planned = Planned::new(&scene, opts)?;
    let Session {
        scene,
        out: data,
        mut renderer,
        ..
    } = Session::open_scene(place, scene)?;
    let out = opts.out.clone().unwrap_or_else(|| data.join("place"));
    crate::util::files::claim_dir(&out)?;
    let reflectors = crate::eval::reflector_names(&scene)?;
    let ctx = compile_context(place, &scene, &data);
    let mut source = setup_mode(
        &ctx,
        &mut renderer,
        Mode::LayeredPem,
        &PemOptions::default(),
        Default::default(),
    )?;
    let settings = TraceSettings {
        width: place.size.0,
        height: place.size.1,
        spp: opts.spp,
        progress: false,
        ..TraceSettings::default()
    };
    let budget = |cost, max| Budget::of(cost, max, &renderer, &scene);
    let bytes = budget(Cost::Bytes, opts.max_bytes.map(|b| b as f64))?;
    let minutes = budget(Cost::Minutes, opts.max_minutes)?;
    for b in bytes.iter().chain(&minutes) {
        planned.limit(b, &scene.orbit)?;
    }
    let references = References::new(&scene, &out.join("reference"), settings)?;
    let start = Instant::now();
    let mut probe = Probe {
        scene: &scene,
        renderer: &mut renderer,
        source: &mut source,
        references: &references,
        reflectors: &reflectors,
        views: 0,
        progress: spinner(),
    };
    let outcome = match planned {
        Planned::Lines(axis, plan) => place_lines(&mut probe, axis, &plan)?,
        Planned::Grid(grid) => place_both(&mut probe, &grid)?,
    };
    probe.progress.finish_and_clear();
    let report = PlaceReport::new(&scene, opts, [bytes, minutes], outcome, start.elapsed());
    report.write(&out)?;
    let scene_file = placed_scene(&place.scene, &scene, &report, &out);
    Ok(report.summary(&out) + &scene_file)
}

/// Placement refines a full grid of lines × rings: a scene whose rings
/// keep only every n-th line (the default teapot's) is refused, saying
/// how to make a dense one.
fn check_dense(scene: &inference::scene::Scene) -> Result<()> {
    if scene.orbit.is_tensor() {
        return Ok(());
    }
    bail!(
        "{}: orbit.ring_line_every = {}: engine place refines a full grid of lines × rings \
         (expected ring_line_every = 1 in the dense scene it starts from; for the orbit's lines \
         alone, a copy of the scene with `rings = 1`, or with `ring_line_every = 1` for the \
         whole grid)",
        scene.origin,
        scene.orbit.ring_line_every
    )
}

/// One axis's lines, refined, and an even placement of as many.
fn place_lines(probe: &mut Probe, axis: Axis, plan_opts: &PlanOptions) -> Result<Outcome> {
    let mut seen = BTreeMap::new();
    let lines_on = probe.scene.orbit.samples;
    let mut measure = |from, to, at| match axis {
        Axis::Azimuth => probe.score(axis, from, to, at, 0),
        // Every azimuth line's view between the rings: the worst counts.
        Axis::Rings => (0..lines_on).try_fold(f64::INFINITY, |worst, line| {
            Ok::<_, anyhow::Error>(worst.min(probe.score(axis, from, to, at, line)?))
        }),
    };
    let plan = plan::place(plan_opts, &mut seen, &mut measure)?;
    let even_lines = plan::uniform(plan_opts.lines, plan.lines.len() as u32);
    let even = plan::measure_intervals(&even_lines, &mut seen, &mut measure)?;
    Ok(Outcome::lines(
        probe.scene,
        axis,
        plan,
        (even_lines, even),
        probe.views,
    ))
}

/// Azimuth lines and rings refined together, and the balanced even grid
/// with at least as many samples ([`grid::even_shape`]).
fn place_both(probe: &mut Probe, grid: &GridOptions) -> Result<Outcome> {
    let mut views = grid::Views::new();
    let mut measure = |axis, from, to, at, other| probe.score(axis, from, to, at, other);
    let plan = grid::place_grid(grid, &mut views, &mut measure)?;
    let shape = grid::even_shape(grid.lines, plan.samples());
    let even_lines = [0, 1].map(|k| plan::uniform(grid.lines[k], shape[k]));
    let even = [
        grid::grid_intervals(&even_lines, 0, &mut views, &mut measure)?,
        grid::grid_intervals(&even_lines, 1, &mut views, &mut measure)?,
    ];
    Ok(Outcome::grid(
        probe.scene,
        plan,
        (even_lines, even),
        probe.views,
    ))
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
    let p = &report.placed;
    let (az, el) = (&p.azimuths_deg, &p.elevations_deg);
    let name = format!("{}_placed", report.scene);
    let path = out.join(format!("{name}.toml"));
    let note = format!("placed by `engine place`: {}", report.reason);
    // (Stacked neighbours are azimuth neighbours, which placing rings keeps.)
    let stacks_samples = report.axis != Placing::Rings
        && dense
            .objects
            .iter()
            .any(|o| o.neighbour_weight() > 0.0 && o.neighbour_deg().is_none());
    let what = match report.axis {
        Placing::Azimuth => format!("azimuths_deg = {az:?}"),
        Placing::Rings => format!("ring_elevations_deg = {el:?}"),
        Placing::Grid => format!("azimuths_deg = {az:?} and ring_elevations_deg = {el:?}"),
    };
    let written = (|| -> Result<()> {
        let (text, source) = Scene::text(scene_arg)?;
        // Written under `out`: mesh files stay where the scene file named them.
        let text = inference::scene::placed::with_mesh_paths_from(&text, &source);
        let rewritten = match report.axis {
            Placing::Azimuth => with_azimuths(&text, &name, az, &note),
            Placing::Rings => with_rings(&text, &name, el, &note),
            Placing::Grid => with_azimuths(&text, &name, az, &note)
                .and_then(|t| with_rings(&t, &name, el, "and its rings, placed with them")),
        };
        let Some(mut text) = rewritten else {
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
            "no placed scene file ({e:#}); put `{what}` in [orbit] instead of its even {}\n",
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
    /// The objects scored together ([`crate::eval::reflector_names`]).
    reflectors: &'a [String],
    /// Views scored so far.
    views: usize,
    progress: indicatif::ProgressBar,
}

impl Probe<'_, '_> {
    /// Reflector PSNR (as `engine eval` scores it) of the view between
    /// lines `at` and `at + 1` of `axis` ([`Axis::probe_deg`]: half a line
    /// past `at`), on line `other` of the other axis (its ring, or its
    /// azimuth line), blended from lines `from` and `to` of `axis` alone.
    fn score(&mut self, axis: Axis, from: u32, to: u32, at: u32, other: u32) -> Result<f64> {
        let o = &self.scene.orbit;
        let between = axis.probe_deg(o, at);
        self.progress
            .set_message(format!("{} {from}..{to}: views past {at}", axis.noun()));
        let pair = [from, to];
        let view = match axis {
            Axis::Azimuth => {
                self.renderer.use_azimuth_lines(Some(&pair));
                View::new(between, o.ring_elevation(other))
            }
            Axis::Rings => {
                self.renderer.use_rings(Some(&pair));
                View::new(o.angle_deg(other), between)
            }
        };
        let db = self.score_view(view);
        self.renderer.use_azimuth_lines(None);
        self.renderer.use_rings(None);
        self.views += 1;
        self.progress.inc(1);
        db
    }

    /// Reflector PSNR of the frame at `view` with the blend as set.
    fn score_view(&mut self, view: View) -> Result<f64> {
        let reference = self.references.get_all(view, self.reflectors)?;
        let eye = view.eye(self.scene);
        // The first frame brings the samples' maps in; the second is scored.
        self.source.draw(self.renderer, self.scene, eye)?;
        self.renderer.settle();
        let pixels = self.source.frame(self.renderer, self.scene, eye)?.1;
        let (width, height) = self.renderer.size();
        match metrics::masked_psnr(&reference.beauty, &pixels, &reference.mask)? {
            Some(db) => Ok(db),
            None => bail!(
                "view at azimuth {}°, elevation {}°: {} covers no pixel at {width}x{height}",
                view.azimuth_deg,
                view.elevation_deg,
                self.reflectors.join("+")
            ),
        }
    }
}
