//! What `engine place` found, as placement.json, placement.png and text.

use super::grid::{GridPlan, Split};
use super::plan::{Interval, Plan, Stop, worst};
use super::{Axis, Budget, Cost, PlaceOptions, Placing};
use crate::eval::plot::{ChartSpec, LegendPosition, Series, xy_chart};
use crate::util::stats::median;
use anyhow::Result;
use inference::scene::Scene;
use std::path::Path;
use std::time::Duration;

/// One placement's lines and the scores of its intervals' middles.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Placement {
    /// Viewpoint samples (lines × the samples each line holds).
    pub samples: u32,
    /// The placed lines (azimuth lines, or rings with `--rings`; with
    /// `--grid` the azimuth lines, and the rings in `rings`).
    pub lines: Vec<u32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rings: Vec<u32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub azimuths_deg: Vec<f32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub elevations_deg: Vec<f32>,
    /// Lowest and median interval score, dB (reflector PSNR at each
    /// interval's held-out view).
    pub worst_db: f64,
    pub median_db: f64,
    pub intervals: Vec<Interval>,
    /// Azimuth (elevation with `--rings`) of each interval's scored
    /// view(s), degrees.
    pub probes_deg: Vec<f32>,
    /// With `--grid`: the intervals between rings (each scored by its
    /// worst view over the placed azimuth lines; `intervals` holds those
    /// between azimuth lines, scored over the placed rings) and the
    /// elevations of their views.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ring_intervals: Vec<Interval>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ring_probes_deg: Vec<f32>,
}

impl Placement {
    fn new(scene: &Scene, axis: Axis, lines: Vec<u32>, intervals: Vec<Interval>) -> Placement {
        let scores: Vec<f64> = intervals.iter().map(|i| i.psnr_db).collect();
        let o = &scene.orbit;
        let positions: Vec<f32> = lines.iter().map(|&l| axis.position_deg(o, l)).collect();
        let (azimuths_deg, elevations_deg) = match axis {
            Axis::Azimuth => (positions, Vec::new()),
            Axis::Rings => (Vec::new(), positions),
        };
        Placement {
            samples: lines.len() as u32 * axis.samples_per_line(o),
            azimuths_deg,
            elevations_deg,
            lines,
            rings: Vec::new(),
            worst_db: worst(&intervals),
            median_db: median_or_inf(&scores),
            probes_deg: probes(o, axis, &intervals),
            intervals,
            ring_intervals: Vec::new(),
            ring_probes_deg: Vec::new(),
        }
    }

    /// A grid placement: azimuth lines × rings and both axes' intervals.
    fn grid(scene: &Scene, [lines, rings]: [Vec<u32>; 2], [az, el]: [Vec<Interval>; 2]) -> Self {
        let o = &scene.orbit;
        let at = |axis: Axis, l: &[u32]| l.iter().map(|&l| axis.position_deg(o, l)).collect();
        let scores: Vec<f64> = az.iter().chain(&el).map(|i| i.psnr_db).collect();
        Placement {
            samples: (lines.len() * rings.len()) as u32,
            azimuths_deg: at(Axis::Azimuth, &lines),
            elevations_deg: at(Axis::Rings, &rings),
            worst_db: worst(&az).min(worst(&el)),
            median_db: median_or_inf(&scores),
            probes_deg: probes(o, Axis::Azimuth, &az),
            ring_probes_deg: probes(o, Axis::Rings, &el),
            lines,
            rings,
            intervals: az,
            ring_intervals: el,
        }
    }
}

fn median_or_inf(scores: &[f64]) -> f64 {
    if scores.is_empty() {
        f64::INFINITY
    } else {
        median(scores)
    }
}

fn probes(o: &inference::scene::Orbit, axis: Axis, intervals: &[Interval]) -> Vec<f32> {
    intervals
        .iter()
        .map(|i| axis.probe_deg(o, i.probe))
        .collect()
}

/// What a placement run found, placed and even, before the report adds
/// the options and budgets.
pub struct Outcome {
    /// With the grid: the dense grid's azimuths and elevations, degrees.
    pub dense_deg: [Vec<f32>; 2],
    pub placed: Placement,
    pub even: Placement,
    pub stop: Stop,
    pub measured: Vec<Interval>,
    pub splits: Vec<Split>,
    pub views_scored: usize,
}

impl Outcome {
    /// One axis's lines.
    pub fn lines(
        scene: &Scene,
        axis: Axis,
        plan: Plan,
        (even_lines, even): (Vec<u32>, Vec<Interval>),
        views_scored: usize,
    ) -> Self {
        Outcome {
            dense_deg: [Vec::new(), Vec::new()],
            placed: Placement::new(scene, axis, plan.lines, plan.intervals),
            even: Placement::new(scene, axis, even_lines, even),
            stop: plan.stop,
            measured: plan.measured,
            splits: Vec::new(),
            views_scored,
        }
    }

    /// Both axes of a grid.
    pub fn grid(
        scene: &Scene,
        plan: GridPlan,
        (even_lines, even): ([Vec<u32>; 2], [Vec<Interval>; 2]),
        views_scored: usize,
    ) -> Self {
        let o = &scene.orbit;
        Outcome {
            dense_deg: [
                (0..o.samples).map(|l| o.angle_deg(l)).collect(),
                o.ring_elevations(),
            ],
            placed: Placement::grid(scene, plan.lines, plan.intervals),
            even: Placement::grid(scene, even_lines, even),
            stop: plan.stop,
            measured: plan.splits.iter().map(|s| s.interval).collect(),
            splits: plan.splits,
            views_scored,
        }
    }
}

/// placement.json.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PlaceReport {
    pub scene: String,
    /// What was placed: azimuth lines, rings or both (`grid`).
    pub axis: Placing,
    /// Samples of the dense compile the placement was chosen from.
    pub dense_samples: u32,
    pub target_db: f64,
    pub max_samples: u32,
    /// The byte budget (`--max-bytes`), what a sample costs in the dense
    /// container and how many samples that buys.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_bytes: Option<Budget>,
    /// The placed samples' container bytes at the dense bytes per sample
    /// (with `--max-bytes`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimated_bytes: Option<u64>,
    /// The compile-minutes budget (`--max-minutes`), the same way.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_minutes: Option<Budget>,
    /// The placed samples' compile minutes at the dense minutes per sample.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimated_minutes: Option<f64>,
    pub start: u32,
    pub spp: u32,
    pub stop: Stop,
    /// Why it stopped where it did, in words.
    pub reason: String,
    pub placed: Placement,
    /// An even placement with as many samples, scored the same way.
    pub even: Placement,
    /// Every interval measured while refining, in order (with `--grid`,
    /// every interval split, its axis in `splits`).
    pub measured: Vec<Interval>,
    /// With `--grid`: the dense grid's azimuth lines and rings, degrees.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dense_azimuths_deg: Vec<f32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dense_elevations_deg: Vec<f32>,
    /// With `--grid`: each split's axis, interval and the samples after it.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub splits: Vec<Split>,
    /// Held-out views rendered and scored.
    pub views_scored: usize,
    pub minutes: f64,
}

impl PlaceReport {
    pub fn new(
        scene: &Scene,
        opts: &PlaceOptions,
        [bytes, minutes]: [Option<Budget>; 2],
        outcome: Outcome,
        took: Duration,
    ) -> PlaceReport {
        let Outcome {
            dense_deg: [dense_azimuths_deg, dense_elevations_deg],
            placed,
            even,
            stop,
            measured,
            splits,
            views_scored,
        } = outcome;
        let reason = match stop {
            Stop::TargetMet => format!(
                "every interval's middle reaches {} dB with {} of {} samples",
                opts.target_db,
                placed.samples,
                scene.orbit.sample_count()
            ),
            Stop::Budget => budget_reason(opts, &[bytes, minutes], &placed),
        };
        let estimated_bytes = bytes.map(|b| b.estimate(placed.samples).round() as u64);
        let estimated_minutes = minutes.map(|b| b.estimate(placed.samples));
        PlaceReport {
            scene: scene.name.clone(),
            axis: opts.placing,
            dense_samples: scene.orbit.sample_count(),
            target_db: opts.target_db,
            max_samples: opts.max_samples,
            max_bytes: bytes,
            estimated_bytes,
            max_minutes: minutes,
            estimated_minutes,
            start: opts.start,
            spp: opts.spp,
            stop,
            reason,
            even,
            placed,
            measured,
            dense_azimuths_deg,
            dense_elevations_deg,
            splits,
            views_scored,
            minutes: took.as_secs_f64() / 60.0,
        }
    }

    /// placement.json and placement.png under `out`.
    pub fn write(&self, out: &Path) -> Result<()> {
        crate::util::files::write_json(&out.join("placement.json"), self)?;
        self.chart(&out.join("placement.png"))
    }

    fn chart(&self, path: &Path) -> Result<()> {
        if self.axis == Placing::Grid {
            return xy_chart(path, &self.grid_chart());
        }
        let series = |name: String, probes: &[f32], intervals: &[Interval]| Series {
            name,
            points: probes
                .iter()
                .zip(intervals)
                .map(|(&x, i)| (f64::from(x), i.psnr_db))
                .collect(),
            labels: Vec::new(),
            connect: true,
        };
        let x = match self.axis {
            Placing::Rings => "elevation of the held-out views between rings (degrees)",
            _ => "azimuth of the held-out view between samples (degrees)",
        };
        let mut spec = ChartSpec::new(
            &format!("Where {} needs its samples", self.scene),
            x,
            "reflector PSNR between samples (dB)",
        );
        spec.legend = LegendPosition::LowerLeft;
        for (kind, p) in [("placed", &self.placed), ("even", &self.even)] {
            let name = format!("{kind}, {} samples", p.samples);
            spec.series.push(series(name, &p.probes_deg, &p.intervals));
        }
        spec.series.retain(|s| !s.points.is_empty());
        if spec.series.is_empty() {
            return Ok(());
        }
        xy_chart(path, &spec)
    }

    /// The grid placement as a map of the viewpoint space: the dense
    /// samples, the even and the placed ones, and each split numbered at
    /// the line it added with the score that asked for it.
    fn grid_chart(&self) -> ChartSpec {
        let [az, el] = [&self.dense_azimuths_deg, &self.dense_elevations_deg];
        let deg = |i: u32, d: &[f32]| f64::from(d.get(i as usize).copied().unwrap_or(0.0));
        let at = |l: &[u32], d: &[f32]| -> Vec<f64> { l.iter().map(|&i| deg(i, d)).collect() };
        let grid = |name: String, lines: &[f64], rings: &[f64]| Series {
            name,
            points: rings
                .iter()
                .flat_map(|&e| lines.iter().map(move |&a| (a, e)))
                .collect(),
            labels: Vec::new(),
            connect: false,
        };
        let all = |d: &[f32]| d.iter().map(|&v| f64::from(v)).collect::<Vec<_>>();
        let mut spec = ChartSpec::new(
            &format!(
                "Where {} needs its samples: {} of {}",
                self.scene, self.placed.samples, self.dense_samples
            ),
            "azimuth (degrees)",
            "elevation above the orbit plane (degrees)",
        );
        spec.legend = LegendPosition::UpperRight;
        // The legend stands right of the grid, not over its corner.
        spec.x_margin_right = 0.6;
        spec.series.push(grid(
            format!("dense, {} samples", self.dense_samples),
            &all(az),
            &all(el),
        ));
        for (kind, p) in [("even", &self.even), ("placed", &self.placed)] {
            spec.series.push(grid(
                format!("{kind}, {} samples (worst {:.2} dB)", p.samples, p.worst_db),
                &at(&p.lines, az),
                &at(&p.rings, el),
            ));
        }
        let (lo_az, lo_el) = (deg(0, az), deg(0, el));
        let (points, labels) = self
            .splits
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let i = s.interval.probe;
                let point = match s.axis {
                    Axis::Azimuth => (deg(i, az), lo_el),
                    Axis::Rings => (lo_az, deg(i, el)),
                };
                (point, format!("{}: {:.2} dB", k + 1, s.interval.psnr_db))
            })
            .unzip();
        spec.series.push(Series {
            name: "split k: the worst interval's score".into(),
            points,
            labels,
            connect: false,
        });
        spec
    }

    /// What `engine place` prints.
    pub fn summary(&self, out: &Path) -> String {
        let p = &self.placed;
        let e = &self.even;
        format!(
            "{}: {} samples placed of {} ({}): worst {:.2} dB, median {:.2} dB between samples \
             (held-out views); an even placement of {} samples: worst {:.2} dB, median {:.2} dB\n\
             {} {}{}\n{} views scored in {:.1} min; wrote {} and {}\n",
            self.scene,
            p.samples,
            self.dense_samples,
            self.reason,
            p.worst_db,
            p.median_db,
            e.samples,
            e.worst_db,
            e.median_db,
            self.axis.noun(),
            match self.axis {
                Placing::Grid => format!("{:?} × {:?}", p.lines, p.rings),
                _ => format!("{:?}", p.lines),
            },
            match (self.estimated_bytes, self.estimated_minutes) {
                (Some(b), Some(m)) => format!(" (~{b} B of container, ~{m:.1} min to compile)"),
                (Some(b), None) => format!(" (~{b} B of container)"),
                (None, Some(m)) => format!(" (~{m:.1} min to compile)"),
                (None, None) => String::new(),
            },
            self.views_scored,
            self.minutes,
            out.join("placement.json").display(),
            out.join("placement.png").display(),
        )
    }
}

/// Why placing stopped at the budget: the binding budget (the fewest
/// samples of `budgets`, within `--max-samples`) and what it cost.
fn budget_reason(opts: &PlaceOptions, budgets: &[Option<Budget>; 2], placed: &Placement) -> String {
    let binding = budgets
        .iter()
        .flatten()
        .filter(|b| b.samples <= opts.max_samples)
        .min_by_key(|b| b.samples);
    let cost = binding.map_or(String::new(), |b| match b.cost {
        Cost::Bytes => format!(
            " ({} B at {:.0} B a sample in the dense container)",
            b.max, b.per_sample
        ),
        Cost::Minutes => format!(
            " ({} min at {:.2} min a sample in the dense compile)",
            b.max, b.per_sample
        ),
    });
    // A grid's next line may cost more samples than are left.
    let budget = binding.map_or(opts.max_samples, |b| b.samples);
    let spent = if opts.placing == Placing::Grid && placed.samples < budget {
        format!(
            "no further split fits the budget of {budget} samples{cost} ({} placed)",
            placed.samples
        )
    } else {
        format!("the budget of {} samples{cost} is spent", placed.samples)
    };
    format!(
        "{spent}; the worst interval ({:.2} dB) is below {} dB",
        placed.worst_db, opts.target_db
    )
}
