//! Where a 2D viewpoint grid needs its samples, azimuth lines and rings
//! placed together (`engine place --grid`). The grid stays lines × rings:
//! every placed line crosses every placed ring. An interval along one
//! axis is scored by its worst held-out view on any placed line of the
//! other axis, and each step splits the worst interval of either axis
//! whose split still fits the budget — a new ring costs one sample per
//! placed azimuth line, a new line one per ring — so the axis whose
//! interpolation fails first gets the samples. Pure: the measurement is a
//! closure, so the rule is tested alone.

use super::Axis;
use super::plan::{Interval, Stop, gaps, uniform, worst};
use anyhow::{Result, bail};
use std::collections::BTreeMap;

/// The grid's two axes, in index order (azimuth lines, then rings).
pub const AXES: [Axis; 2] = [Axis::Azimuth, Axis::Rings];

/// What the joint refinement may spend and what it aims for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridOptions {
    /// Dense lines per axis: azimuth lines, rings (each ≥ 2).
    pub lines: [u32; 2],
    /// Lines per axis placed evenly before any measurement, both ends
    /// included (clamped to the dense lines).
    pub start: [u32; 2],
    /// At most this many samples (lines × rings) in the end.
    pub max_samples: u32,
    /// Every interval's held-out views at least this PSNR, dB.
    pub target_db: f64,
}

impl GridOptions {
    /// The even start lines of each axis.
    pub fn start_lines(&self) -> [Vec<u32>; 2] {
        [0, 1].map(|k| uniform(self.lines[k], self.start[k].min(self.lines[k])))
    }

    /// Samples of the start grid.
    pub fn start_samples(&self) -> u32 {
        let [a, r] = self.start_lines();
        (a.len() * r.len()) as u32
    }

    /// An error naming what cannot be placed.
    pub fn validate(&self) -> Result<()> {
        if self.lines.iter().any(|&l| l < 2) || self.start.iter().any(|&s| s < 2) {
            bail!(
                "a grid of {} azimuth lines × {} rings from {} × {} start lines: expected at \
                 least 2 of each",
                self.lines[0],
                self.lines[1],
                self.start[0],
                self.start[1]
            );
        }
        if self.max_samples < self.start_samples() {
            bail!(
                "--max-samples {}: the start grid alone is {} samples (expected a budget of at \
                 least that)",
                self.max_samples,
                self.start_samples()
            );
        }
        if !self.target_db.is_finite() {
            bail!("--target-db {}: expected a finite number", self.target_db);
        }
        Ok(())
    }
}

/// One step of the refinement: the interval split along `axis` and the
/// grid's samples after it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Split {
    pub axis: Axis,
    pub interval: Interval,
    pub samples: u32,
}

/// The joint placement and how it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct GridPlan {
    /// The placed lines of each axis, increasing.
    pub lines: [Vec<u32>; 2],
    /// Each axis's final intervals that have a line inside.
    pub intervals: [Vec<Interval>; 2],
    pub stop: Stop,
    /// Every split, in order.
    pub splits: Vec<Split>,
}

impl GridPlan {
    pub fn samples(&self) -> u32 {
        (self.lines[0].len() * self.lines[1].len()) as u32
    }

    /// The lowest score of both axes' intervals (+∞ when none).
    pub fn worst_db(&self) -> f64 {
        worst(&self.intervals[0]).min(worst(&self.intervals[1]))
    }
}

/// Scored views, memoised: (axis index, from, to, the other axis's line)
/// → dB, so a view is measured once whatever asks.
pub type Views = BTreeMap<(usize, u32, u32, u32), f64>;

/// The intervals of axis `k` of `lines` that have a line inside, each
/// scored by its worst view on the other axis's placed lines.
/// `measure(axis, from, to, probe, other)` scores the view at line
/// `probe` of `axis` blended from lines `from` and `to`, sitting on line
/// `other` of the other axis.
pub fn grid_intervals(
    lines: &[Vec<u32>; 2],
    k: usize,
    views: &mut Views,
    measure: &mut impl FnMut(Axis, u32, u32, u32, u32) -> Result<f64>,
) -> Result<Vec<Interval>> {
    let mut out = Vec::new();
    for (from, to, probe) in gaps(&lines[k]) {
        let mut psnr_db = f64::INFINITY;
        for &other in &lines[1 - k] {
            let db = match views.get(&(k, from, to, other)) {
                Some(db) => *db,
                None => {
                    let db = measure(AXES[k], from, to, probe, other)?;
                    views.insert((k, from, to, other), db);
                    db
                }
            };
            psnr_db = psnr_db.min(db);
        }
        out.push(Interval {
            from,
            to,
            probe,
            psnr_db,
        });
    }
    Ok(out)
}

/// Starts from the even start grid and splits, at its middle line, the
/// worst interval of either axis that is below the target and whose split
/// fits the budget, until every interval reaches the target (or none
/// below it fits).
pub fn place_grid(
    opts: &GridOptions,
    views: &mut Views,
    mut measure: impl FnMut(Axis, u32, u32, u32, u32) -> Result<f64>,
) -> Result<GridPlan> {
    opts.validate()?;
    let mut lines = opts.start_lines();
    let mut splits = Vec::new();
    loop {
        let intervals = [
            grid_intervals(&lines, 0, views, &mut measure)?,
            grid_intervals(&lines, 1, views, &mut measure)?,
        ];
        let after = |k: usize| {
            let n = |j: usize| lines[j].len() as u32 + u32::from(j == k);
            n(0) * n(1)
        };
        let below: Vec<(usize, Interval)> = (0..2)
            .flat_map(|k| intervals[k].iter().map(move |i| (k, *i)))
            .filter(|(_, i)| i.psnr_db < opts.target_db)
            .collect();
        let pick = below
            .iter()
            .filter(|(k, _)| after(*k) <= opts.max_samples)
            .min_by(|a, b| a.1.psnr_db.total_cmp(&b.1.psnr_db))
            .copied();
        let Some((k, worst)) = pick else {
            let stop = if below.is_empty() {
                Stop::TargetMet
            } else {
                Stop::Budget
            };
            return Ok(GridPlan {
                lines,
                intervals,
                stop,
                splits,
            });
        };
        let samples = after(k);
        let at = lines[k].partition_point(|&l| l < worst.probe);
        lines[k].insert(at, worst.probe);
        splits.push(Split {
            axis: AXES[k],
            interval: worst,
            samples,
        });
    }
}

/// The even grid a placement of `samples` samples is compared with: the
/// shape whose lines and rings take the most nearly equal fractions of the
/// dense grid's (`dense` lines per axis), the fewest samples among those,
/// and at least `samples` (so the even grid never has fewer samples than
/// the placement it is compared with); the dense grid when none is that big.
pub fn even_shape(dense: [u32; 2], samples: u32) -> [u32; 2] {
    let fraction = |n: u32, of: u32| f64::from(n - 1) / f64::from(of.max(2) - 1);
    let mut best: Option<(f64, u32, [u32; 2])> = None;
    for a in 2..=dense[0].max(2) {
        for r in 2..=dense[1].max(2) {
            if a * r < samples {
                continue;
            }
            let skew = (fraction(a, dense[0]) - fraction(r, dense[1])).abs();
            let better = best
                .is_none_or(|(s, n, _)| skew < s - 1e-9 || ((skew - s).abs() <= 1e-9 && a * r < n));
            if better {
                best = Some((skew, a * r, [a, r]));
            }
        }
    }
    best.map_or(dense, |(_, _, shape)| shape)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(target_db: f64, max_samples: u32) -> GridOptions {
        GridOptions {
            lines: [17, 9],
            start: [2, 2],
            max_samples,
            target_db,
        }
    }

    /// Blending error grows with the interval's width: along the rings
    /// 2× faster per line than along the azimuth lines, 3× on azimuth
    /// lines 12..16; along the azimuth lines 1.2× on rings 6..8.
    fn scene(axis: Axis, from: u32, to: u32, _probe: u32, other: u32) -> Result<f64> {
        let busy = match axis {
            Axis::Rings if other >= 12 => 3.0,
            Axis::Rings => 2.0,
            Axis::Azimuth if other >= 6 => 1.2,
            Axis::Azimuth => 1.0,
        };
        Ok(60.0 - 20.0 * (f64::from(to - from) * busy).log10())
    }

    #[test]
    fn the_axis_that_fails_first_gets_the_lines_until_the_target_is_met() {
        let mut views = Views::new();
        let plan = place_grid(&opts(40.0, 1000), &mut views, scene).expect("plan");
        assert_eq!(plan.stop, Stop::TargetMet, "{plan:?}");
        assert!(plan.worst_db() >= 40.0, "{plan:?}");
        // 40 dB needs width × busy ≤ 10: azimuth lines 8 apart (busy 1.2
        // on the top ring), rings 2 apart (busy 3 on the last line).
        assert_eq!(plan.lines, [vec![0, 8, 16], vec![0, 2, 4, 6, 8]]);
        assert_eq!(plan.samples(), 15);
        // The worst interval of either axis went first: the rings (32.4
        // against 34.3 dB), then the azimuth span, then the rings' halves.
        let axes: Vec<Axis> = plan.splits.iter().map(|s| s.axis).collect();
        use Axis::{Azimuth, Rings};
        assert_eq!(axes, [Rings, Azimuth, Rings, Rings], "{plan:?}");
        let samples: Vec<u32> = plan.splits.iter().map(|s| s.samples).collect();
        assert_eq!(samples, [6, 9, 12, 15]);
        // Every view was measured once: re-scoring the final grid reuses all.
        let again = grid_intervals(&plan.lines, 1, &mut views, &mut |_, _, _, _, _| {
            bail!("measured twice")
        });
        assert_eq!(again.expect("memoised"), plan.intervals[1]);
    }

    #[test]
    fn an_interval_scores_its_worst_view_over_the_other_axis() {
        // Azimuth lines 0..16 measured on rings 0 and 8: ring 8 is busier.
        let lines = [vec![0, 16], vec![0, 8]];
        let mut calls = Vec::new();
        let got = grid_intervals(&lines, 0, &mut Views::new(), &mut |a, f, t, p, o| {
            calls.push((a, f, t, p, o));
            scene(a, f, t, p, o)
        })
        .expect("scored");
        assert_eq!(
            calls,
            [(Axis::Azimuth, 0, 16, 8, 0), (Axis::Azimuth, 0, 16, 8, 8)]
        );
        let busy = scene(Axis::Azimuth, 0, 16, 8, 8).expect("db");
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].psnr_db, busy);
    }

    #[test]
    fn the_budget_counts_samples_and_a_split_that_does_not_fit_is_skipped() {
        // 2×2 start; a ring costs 2 samples and a line 2 at first. With 7
        // samples at most the grid can reach 3×2 or 2×3, never 3×3.
        let plan = place_grid(&opts(99.0, 7), &mut Views::new(), scene).expect("plan");
        assert_eq!(plan.stop, Stop::Budget);
        assert_eq!(plan.samples(), 6, "{plan:?}");
        assert_eq!(plan.splits.len(), 1);
        // The rings fail first in this scene.
        assert_eq!(plan.splits[0].axis, Axis::Rings);
    }

    #[test]
    fn the_even_grid_compared_is_balanced_and_never_smaller() {
        // 7 × 7 dense: 14 placed samples meet a 4 × 4 even grid, 21 a 5 × 5.
        assert_eq!(even_shape([7, 7], 14), [4, 4]);
        assert_eq!(even_shape([7, 7], 21), [5, 5]);
        assert_eq!(even_shape([7, 7], 4), [2, 2]);
        // 3 lines × 5 rings: half of each, 2 × 3.
        assert_eq!(even_shape([3, 5], 6), [2, 3]);
        // Beyond the dense grid: the dense grid.
        assert_eq!(even_shape([3, 5], 99), [3, 5]);
    }

    #[test]
    fn bad_options_and_failing_measurements_are_errors() {
        let ok = |_, _, _, _, _| Ok(50.0);
        for o in [
            GridOptions {
                lines: [1, 9],
                ..opts(40.0, 100)
            },
            GridOptions {
                start: [2, 1],
                ..opts(40.0, 100)
            },
            opts(40.0, 3),
            opts(f64::NAN, 100),
        ] {
            assert!(place_grid(&o, &mut Views::new(), ok).is_err(), "{o:?}");
        }
        let failing = place_grid(&opts(40.0, 100), &mut Views::new(), |_, _, _, _, _| {
            bail!("no device")
        });
        assert!(format!("{:#}", failing.expect_err("fails")).contains("no device"));
    }
}
