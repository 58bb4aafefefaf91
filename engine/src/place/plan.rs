//! Where a 1D orbit needs its samples: greedy refinement of azimuth lines
//! by the measured error of blending between neighbours. Pure: the
//! measurement is a closure (in `engine place`, a rendered frame at the
//! interval's middle against a traced view), so the rule is tested alone.

use anyhow::{Result, bail};
use std::collections::BTreeMap;

/// What the refinement may spend and what it aims for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanOptions {
    /// Lines of the dense grid the samples are chosen from (≥ 2).
    pub lines: u32,
    /// Lines placed before any measurement, evenly, both ends included.
    pub start: u32,
    /// At most this many lines in the end (the budget).
    pub max_samples: u32,
    /// Every interval's middle view at least this PSNR, dB.
    pub target_db: f64,
}

impl PlanOptions {
    /// An error naming what cannot be placed: fewer than 2 lines or start
    /// lines, a budget below the start lines, a target that is no number.
    pub fn validate(&self) -> Result<()> {
        if self.lines < 2 || self.start < 2 || self.max_samples < self.start.min(self.lines) {
            bail!(
                "placement over {} lines from {} start lines with at most {}: expected at least \
                 2 lines, 2 start lines and a budget (--max-samples) of at least the start lines",
                self.lines,
                self.start,
                self.max_samples
            );
        }
        if !self.target_db.is_finite() {
            bail!("--target-db {}: expected a finite number", self.target_db);
        }
        Ok(())
    }
}

/// One interval between neighbouring placed lines, the line in its middle
/// it would split at (`probe`) and the score of a view there blended from
/// its two ends (which view is the measurer's: `engine place` scores the
/// one half a line past `probe`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Interval {
    pub from: u32,
    pub to: u32,
    pub probe: u32,
    pub psnr_db: f64,
}

/// Why the refinement stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// Every interval's middle reaches the target.
    TargetMet,
    /// The budget of lines is spent; the worst interval is still below.
    Budget,
}

/// The placement and how it was found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Plan {
    /// The placed lines, increasing.
    pub lines: Vec<u32>,
    /// The final intervals that have a line inside (neighbouring lines
    /// need no blend), in order.
    pub intervals: Vec<Interval>,
    pub stop: Stop,
    /// Every measurement made, in order (refinement history).
    pub measured: Vec<Interval>,
}

impl Plan {
    /// The lowest interval score (+∞ without intervals).
    pub fn worst_db(&self) -> f64 {
        worst(&self.intervals)
    }
}

/// The lowest score of `intervals` (+∞ when empty).
pub fn worst(intervals: &[Interval]) -> f64 {
    intervals
        .iter()
        .map(|i| i.psnr_db)
        .fold(f64::INFINITY, f64::min)
}

/// How many samples fit in `max_bytes` of container, from the dense
/// container's `dense_bytes` over its `dense_lines` samples. The encoder
/// codes at a fixed ratio, so a container's bytes grow in proportion to
/// the samples it holds and the dense bytes per sample carry over.
pub fn samples_within_bytes(max_bytes: u64, dense_bytes: u64, dense_lines: u32) -> u32 {
    if dense_bytes == 0 {
        return u32::MAX;
    }
    let fit = u128::from(max_bytes) * u128::from(dense_lines) / u128::from(dense_bytes);
    u32::try_from(fit).unwrap_or(u32::MAX)
}

/// `count` lines spread evenly over `lines`, both ends included.
pub fn uniform(lines: u32, count: u32) -> Vec<u32> {
    let (n, c) = (lines.max(1), count.clamp(1, lines.max(1)));
    if c == 1 {
        return vec![0];
    }
    let mut out: Vec<u32> = (0..c)
        .map(|i| (i as f64 * (n - 1) as f64 / (c - 1) as f64).round() as u32)
        .collect();
    out.dedup();
    out
}

/// The intervals between neighbouring `lines` with a dense line inside
/// (neighbouring lines need no blend), each with the middle line it
/// would split at: `(from, to, probe)`.
pub fn gaps(lines: &[u32]) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
    lines
        .windows(2)
        .filter(|w| w[1] - w[0] >= 2)
        .map(|w| (w[0], w[1], w[0] + (w[1] - w[0]) / 2))
}

/// Measures each interval of `lines` with a line inside (memoised in
/// `seen`, so an interval is measured once whatever asks).
pub fn measure_intervals(
    lines: &[u32],
    seen: &mut BTreeMap<(u32, u32), Interval>,
    measure: &mut impl FnMut(u32, u32, u32) -> Result<f64>,
) -> Result<Vec<Interval>> {
    let mut out = Vec::new();
    for (from, to, probe) in gaps(lines) {
        let interval = match seen.get(&(from, to)) {
            Some(i) => *i,
            None => {
                let psnr_db = measure(from, to, probe)?;
                let i = Interval {
                    from,
                    to,
                    probe,
                    psnr_db,
                };
                seen.insert((from, to), i);
                i
            }
        };
        out.push(interval);
    }
    Ok(out)
}

/// Starts from `opts.start` even lines and splits the worst interval at
/// its middle line (beside the view just measured, so the new sample is
/// where the error was) until every interval reaches the target or the
/// budget is spent. `measure(from, to, probe)` scores a view at line
/// `probe` blended from lines `from` and `to`.
pub fn place(
    opts: &PlanOptions,
    seen: &mut BTreeMap<(u32, u32), Interval>,
    mut measure: impl FnMut(u32, u32, u32) -> Result<f64>,
) -> Result<Plan> {
    opts.validate()?;
    let mut lines = uniform(opts.lines, opts.start);
    let mut order: Vec<Interval> = Vec::new();
    loop {
        let intervals = measure_intervals(&lines, seen, &mut measure)?;
        for i in &intervals {
            if !order.contains(i) {
                order.push(*i);
            }
        }
        let Some(worst) = intervals
            .iter()
            .min_by(|a, b| a.psnr_db.total_cmp(&b.psnr_db))
        else {
            return Ok(finish(lines, intervals, Stop::TargetMet, order));
        };
        if worst.psnr_db >= opts.target_db {
            return Ok(finish(lines, intervals, Stop::TargetMet, order));
        }
        if lines.len() as u32 >= opts.max_samples {
            return Ok(finish(lines, intervals, Stop::Budget, order));
        }
        let at = lines.partition_point(|&l| l < worst.probe);
        lines.insert(at, worst.probe);
    }
}

fn finish(lines: Vec<u32>, intervals: Vec<Interval>, stop: Stop, measured: Vec<Interval>) -> Plan {
    Plan {
        lines,
        intervals,
        stop,
        measured,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(target_db: f64, max_samples: u32) -> PlanOptions {
        PlanOptions {
            lines: 101,
            start: 3,
            max_samples,
            target_db,
        }
    }

    /// Blending error grows with the interval's width, much faster where
    /// the scene changes quickly (lines 60 to 80).
    fn scene_error(from: u32, to: u32, probe: u32) -> Result<f64> {
        let busy = if (60..80).contains(&probe) { 8.0 } else { 1.0 };
        Ok(60.0 - 20.0 * ((to - from) as f64 * busy).log10())
    }

    #[test]
    fn lines_go_where_the_error_is_until_the_target_is_met() {
        let plan = place(&opts(40.0, 101), &mut BTreeMap::new(), scene_error).expect("plan");
        assert_eq!(plan.stop, Stop::TargetMet);
        assert!(plan.worst_db() >= 40.0, "{plan:?}");
        let busy = plan.lines.windows(2).filter(|w| w[0] >= 60 && w[1] <= 80);
        let quiet = plan.lines.windows(2).filter(|w| w[1] <= 50);
        let width = |w: &[u32]| w[1] - w[0];
        assert!(busy.clone().all(|w| width(w) <= 2), "{:?}", plan.lines);
        assert!(quiet.clone().all(|w| width(w) >= 6), "{:?}", plan.lines);
        // Fewer lines than a uniform grid as fine as the busy part needs.
        assert!(plan.lines.len() < 50, "{}", plan.lines.len());
        assert!(plan.lines.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(
            (plan.lines[0], *plan.lines.last().expect("lines")),
            (0, 100)
        );
    }

    #[test]
    fn a_byte_budget_holds_the_samples_whose_share_of_the_dense_bytes_fits() {
        // 100 dense samples in 4,000,000 B: 40,000 B a sample.
        assert_eq!(samples_within_bytes(1_000_000, 4_000_000, 100), 25);
        assert_eq!(samples_within_bytes(999_999, 4_000_000, 100), 24);
        assert_eq!(samples_within_bytes(39_999, 4_000_000, 100), 0);
        assert_eq!(samples_within_bytes(u64::MAX, 1, 100), u32::MAX);
        assert_eq!(samples_within_bytes(10, 0, 100), u32::MAX);
    }

    #[test]
    fn the_budget_stops_refinement_and_each_interval_is_measured_once() {
        let mut calls = 0;
        let mut seen = BTreeMap::new();
        let plan = place(&opts(99.0, 9), &mut seen, |a, b, p| {
            calls += 1;
            scene_error(a, b, p)
        })
        .expect("plan");
        assert_eq!((plan.stop, plan.lines.len()), (Stop::Budget, 9));
        assert!(plan.worst_db() < 99.0);
        assert_eq!(calls, plan.measured.len());
        // Re-measuring the same lines reuses every score.
        let again = measure_intervals(&plan.lines, &mut seen, &mut |_, _, _| {
            bail!("measured twice")
        });
        assert_eq!(again.expect("memoised"), plan.intervals);
    }

    #[test]
    fn bad_options_and_failing_measurements_are_errors() {
        let ok = |_, _, _| Ok(50.0);
        for o in [
            PlanOptions {
                lines: 1,
                ..opts(40.0, 10)
            },
            PlanOptions {
                start: 1,
                ..opts(40.0, 10)
            },
            opts(40.0, 2),
            opts(f64::NAN, 10),
        ] {
            assert!(place(&o, &mut BTreeMap::new(), ok).is_err(), "{o:?}");
        }
        let failing = place(&opts(40.0, 10), &mut BTreeMap::new(), |_, _, _| {
            bail!("no device")
        });
        assert!(format!("{:#}", failing.expect_err("fails")).contains("no device"));
        // Two lines side by side: nothing to blend, nothing to measure.
        let dense = PlanOptions {
            lines: 2,
            start: 2,
            max_samples: 2,
            target_db: 40.0,
        };
        let plan = place(&dense, &mut BTreeMap::new(), |_, _, _| bail!("measured")).expect("plan");
        assert_eq!((plan.lines, plan.stop), (vec![0, 1], Stop::TargetMet));
    }

    #[test]
    fn uniform_lines_span_both_ends() {
        assert_eq!(uniform(100, 5), [0, 25, 50, 74, 99]);
        assert_eq!(uniform(100, 1), [0]);
        assert_eq!(uniform(3, 10), [0, 1, 2]);
    }
}
