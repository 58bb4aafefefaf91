//! What `engine place` found, as placement.json, placement.png and text.

use super::plan::{Interval, Plan, Stop, worst};
use super::{Axis, Budget, Cost, PlaceOptions};
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
    /// The placed lines (azimuth lines, or rings with `--rings`).
    pub lines: Vec<u32>,
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
            worst_db: worst(&intervals),
            median_db: if scores.is_empty() {
                f64::INFINITY
            } else {
                median(&scores)
            },
            probes_deg: intervals
                .iter()
                .map(|i| axis.probe_deg(o, i.probe))
                .collect(),
            intervals,
        }
    }
}

/// placement.json.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PlaceReport {
    pub scene: String,
    /// What was placed: azimuth lines or rings.
    pub axis: Axis,
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
    /// Every interval measured while refining, in order.
    pub measured: Vec<Interval>,
    pub minutes: f64,
}

impl PlaceReport {
    pub fn new(
        scene: &Scene,
        opts: &PlaceOptions,
        [bytes, minutes]: [Option<Budget>; 2],
        plan: Plan,
        even_lines: Vec<u32>,
        even: Vec<Interval>,
        took: Duration,
    ) -> PlaceReport {
        let axis = opts.axis;
        let placed = Placement::new(scene, axis, plan.lines, plan.intervals);
        let reason = match plan.stop {
            Stop::TargetMet => format!(
                "every interval's middle reaches {} dB with {} of {} samples",
                opts.target_db,
                placed.samples,
                scene.orbit.sample_count()
            ),
            Stop::Budget => format!(
                "the budget of {} samples{} is spent; the worst interval ({:.2} dB) is below {} dB",
                placed.samples,
                bytes
                    .iter()
                    .chain(&minutes)
                    .filter(|b| b.samples <= opts.max_samples)
                    .min_by_key(|b| b.samples)
                    .map_or(String::new(), |b| match b.cost {
                        Cost::Bytes => format!(
                            " ({} B at {:.0} B a sample in the dense container)",
                            b.max, b.per_sample
                        ),
                        Cost::Minutes => format!(
                            " ({} min at {:.2} min a sample in the dense compile)",
                            b.max, b.per_sample
                        ),
                    }),
                placed.worst_db,
                opts.target_db
            ),
        };
        let estimated_bytes = bytes.map(|b| b.estimate(placed.samples).round() as u64);
        let estimated_minutes = minutes.map(|b| b.estimate(placed.samples));
        PlaceReport {
            scene: scene.name.clone(),
            axis,
            dense_samples: scene.orbit.sample_count(),
            target_db: opts.target_db,
            max_samples: opts.max_samples,
            max_bytes: bytes,
            estimated_bytes,
            max_minutes: minutes,
            estimated_minutes,
            start: opts.start,
            spp: opts.spp,
            stop: plan.stop,
            reason,
            even: Placement::new(scene, axis, even_lines, even),
            placed,
            measured: plan.measured,
            minutes: took.as_secs_f64() / 60.0,
        }
    }

    /// placement.json and placement.png under `out`.
    pub fn write(&self, out: &Path) -> Result<()> {
        crate::util::files::write_json(&out.join("placement.json"), self)?;
        self.chart(&out.join("placement.png"))
    }

    fn chart(&self, path: &Path) -> Result<()> {
        let series = |name: String, p: &Placement| Series {
            name,
            points: p
                .probes_deg
                .iter()
                .zip(&p.intervals)
                .map(|(&x, i)| (f64::from(x), i.psnr_db))
                .collect(),
            labels: Vec::new(),
            connect: true,
        };
        let x = match self.axis {
            Axis::Azimuth => "azimuth of the held-out view between samples (degrees)",
            Axis::Rings => "elevation of the held-out views between rings (degrees)",
        };
        let mut spec = ChartSpec::new(
            &format!("Where {} needs its samples", self.scene),
            x,
            "reflector PSNR between samples (dB)",
        );
        spec.legend = LegendPosition::LowerLeft;
        spec.series = vec![
            series(
                format!("placed, {} samples", self.placed.samples),
                &self.placed,
            ),
            series(format!("even, {} samples", self.even.samples), &self.even),
        ];
        spec.series.retain(|s| !s.points.is_empty());
        if spec.series.is_empty() {
            return Ok(());
        }
        xy_chart(path, &spec)
    }

    /// What `engine place` prints.
    pub fn summary(&self, out: &Path) -> String {
        let p = &self.placed;
        let e = &self.even;
        format!(
            "{}: {} samples placed of {} ({}): worst {:.2} dB, median {:.2} dB between samples \
             (held-out views); an even placement of {} samples: worst {:.2} dB, median {:.2} dB\n\
             {} {:?}{}\n{} intervals measured in {:.1} min; wrote {} and {}\n",
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
            p.lines,
            match (self.estimated_bytes, self.estimated_minutes) {
                (Some(b), Some(m)) => format!(" (~{b} B of container, ~{m:.1} min to compile)"),
                (Some(b), None) => format!(" (~{b} B of container)"),
                (None, Some(m)) => format!(" (~{m:.1} min to compile)"),
                (None, None) => String::new(),
            },
            self.measured.len() + e.intervals.len(),
            self.minutes,
            out.join("placement.json").display(),
            out.join("placement.png").display(),
        )
    }
}
