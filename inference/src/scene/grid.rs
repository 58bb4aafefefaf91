//! The viewpoint space a scene's maps are sampled over: a grid of orbit
//! azimuths × elevations above the orbit plane (a 1D orbit is one row at
//! elevation 0). Lines need not be evenly spaced — the compile step places
//! them where the scene needs them — and sample `k` is `(i_az, i_el)` with
//! `k = i_az + n_az · i_el`. Rings above the first may keep every n-th
//! line only (`ring_line_every`), numbered after the first ring's. A view
//! between lines blends the corners of its cell bilinearly, or those of the
//! triangle that holds it (`triangles`).

use super::camera::Orbit;
use super::ring_lines::RingLines;
use glam::Vec3;

mod triangles;
pub use triangles::ViewBlend;

/// Weights below this count as "exactly on a sample": no blend.
pub const ON_SAMPLE: f32 = 1e-4;

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ViewGrid {
    /// Orbit azimuths of the grid's lines, degrees, increasing.
    pub azimuths_deg: Vec<f32>,
    /// Elevations above the orbit plane, degrees, increasing.
    pub elevations_deg: Vec<f32>,
    /// The azimuth lines views blend between (indices, increasing), when
    /// only some are: `engine place` measures a subset of a dense grid
    /// this way, sample indices unchanged. `None`: every line.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub azimuths_used: Option<Vec<u32>>,
    /// Likewise the elevation rings views blend between (`engine place
    /// --rings`). `None`: every ring.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elevations_used: Option<Vec<u32>>,
    /// The rings above the first hold every this-many lines and the last
    /// (0 or 1: every line, a tensor grid).
    #[serde(default, skip_serializing_if = "is_tensor")]
    pub ring_line_every: u32,
}

fn is_tensor(every: &u32) -> bool {
    *every <= 1
}

/// The samples one view draws from, nearest first, weights summing to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleBlend {
    pub samples: Vec<(u32, f32)>,
}

impl SampleBlend {
    pub fn one(sample: u32) -> Self {
        Self {
            samples: vec![(sample, 1.0)],
        }
    }
    /// The nearest sample (the largest weight).
    pub fn first(&self) -> u32 {
        self.samples.first().map_or(0, |s| s.0)
    }
    pub fn indices(&self) -> impl Iterator<Item = u32> + '_ {
        self.samples.iter().map(|s| s.0)
    }
}

impl ViewGrid {
    /// The orbit's own samples: `samples` azimuths `step_deg` apart, one row.
    pub fn from_orbit(orbit: &Orbit) -> Self {
        Self {
            azimuths_deg: (0..orbit.samples.max(1))
                .map(|k| orbit.angle_deg(k))
                .collect(),
            elevations_deg: orbit.ring_elevations(),
            azimuths_used: None,
            elevations_used: None,
            ring_line_every: orbit.ring_line_every,
        }
    }

    /// How the samples are numbered over the rings' lines.
    fn ring_lines(&self) -> RingLines {
        RingLines {
            lines: self.azimuths_deg.len() as u32,
            every: self.ring_line_every,
        }
    }

    /// The same grid blending between `lines` only (azimuth line indices;
    /// out-of-range ones dropped, sorted, deduplicated; empty or `None`
    /// means every line).
    pub fn with_azimuths_used(mut self, lines: Option<&[u32]>) -> Self {
        self.azimuths_used = subset(lines, self.azimuths_deg.len());
        self
    }

    /// The same grid blending between `rings` only (elevation ring
    /// indices, as [`ViewGrid::with_azimuths_used`] takes lines).
    pub fn with_elevations_used(mut self, rings: Option<&[u32]>) -> Self {
        self.elevations_used = subset(rings, self.elevations_deg.len());
        self
    }

    /// The azimuth lines in use on ring `ring`, every `spacing`-th of them.
    fn azimuth_lines(&self, spacing: u32, ring: u32) -> Vec<usize> {
        let on_ring = self.ring_lines().on_ring(ring);
        let mut lines = used(&self.azimuths_used, self.azimuths_deg.len(), spacing);
        if ring > 0 && self.ring_line_every > 1 {
            lines.retain(|&i| on_ring.binary_search(&(i as u32)).is_ok());
        }
        lines
    }

    /// The elevation rings in use, every `spacing`-th of them.
    fn elevation_lines(&self, spacing: u32) -> Vec<usize> {
        used(&self.elevations_used, self.elevations_deg.len(), spacing)
    }

    pub fn len(&self) -> u32 {
        self.ring_lines().count(self.elevations_deg.len() as u32)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `(i_az, i_el)` of sample `k`.
    pub fn coords(&self, k: u32) -> (u32, u32) {
        self.ring_lines().coords(k)
    }

    /// Sample `k` at line `i_az` of ring `i_el` (on a ring that skips
    /// lines, its nearest line at or before `i_az`).
    pub fn index(&self, i_az: u32, i_el: u32) -> u32 {
        self.ring_lines().index(i_az, i_el)
    }

    /// (azimuth, elevation) of sample `k`, degrees.
    pub fn angles(&self, k: u32) -> (f32, f32) {
        let (a, e) = self.coords(k);
        (
            self.azimuths_deg.get(a as usize).copied().unwrap_or(0.0),
            self.elevations_deg.get(e as usize).copied().unwrap_or(0.0),
        )
    }

    /// Where sample `k`'s eye is on `orbit`.
    pub fn eye(&self, orbit: &Orbit, k: u32) -> Vec3 {
        let (az, el) = self.angles(k);
        orbit.eye(az, el)
    }

    /// The samples a view at (`azimuth`, `elevation`) draws: the corners of
    /// its cell with bilinear weights (views beyond the grid clamp to its
    /// edge), using every `spacing`-th line of each dimension only; with
    /// `blend` false, the nearest alone. Finite for every input.
    pub fn blend(&self, azimuth: f32, elevation: f32, spacing: u32, blend: bool) -> SampleBlend {
        let azimuth = unwrap_around(&self.azimuths_deg, azimuth);
        let elevation_lines = self.elevation_lines(spacing);
        let (e0, e1, te) = bracket(&self.elevations_deg, &elevation_lines, elevation);
        let mut samples: Vec<(u32, f32)> = Vec::with_capacity(4);
        let mut nearest = None;
        for (i_el, we) in [(e0, 1.0 - te), (e1, te)] {
            let lines = self.azimuth_lines(spacing, i_el);
            let (a0, a1, ta) = bracket(&self.azimuths_deg, &lines, azimuth);
            nearest.get_or_insert(self.index(a0, i_el));
            for (i_az, wa) in [(a0, 1.0 - ta), (a1, ta)] {
                let w = wa * we;
                let k = self.index(i_az, i_el);
                match samples.iter_mut().find(|s| s.0 == k) {
                    Some(s) => s.1 += w,
                    None => samples.push((k, w)),
                }
            }
        }
        SampleBlend::normalized(samples, blend, nearest.unwrap_or(0))
    }
}

impl SampleBlend {
    /// `samples` (index, weight) without the negligible ones, nearest
    /// first, weights summing to 1 (with `blend` false the nearest alone);
    /// `fallback` alone when no weight is usable.
    fn normalized(mut samples: Vec<(u32, f32)>, blend: bool, fallback: u32) -> Self {
        samples.retain(|s| s.1 >= ON_SAMPLE);
        samples.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        if !blend {
            samples.truncate(1);
        }
        let total: f32 = samples.iter().map(|s| s.1).sum();
        if samples.is_empty() || !total.is_finite() || total <= 0.0 {
            return SampleBlend::one(fallback);
        }
        samples.iter_mut().for_each(|s| s.1 /= total);
        SampleBlend { samples }
    }
}

impl ViewGrid {
    /// The size (degrees) of the cell around (`azimuth`, `elevation`) in
    /// each dimension, every `spacing`-th line (the edge cell's beyond the
    /// grid; 0 for a dimension with one line).
    pub fn cell_size(&self, azimuth: f32, elevation: f32, spacing: u32) -> (f32, f32) {
        let azimuth = unwrap_around(&self.azimuths_deg, azimuth);
        let ring = bracket(
            &self.elevations_deg,
            &self.elevation_lines(spacing),
            elevation,
        )
        .0;
        (
            span(
                &self.azimuths_deg,
                &self.azimuth_lines(spacing, ring),
                azimuth,
            ),
            span(
                &self.elevations_deg,
                &self.elevation_lines(spacing),
                elevation,
            ),
        )
    }
}

/// `lines` below `n`, sorted and deduplicated; None when that leaves none.
fn subset(lines: Option<&[u32]>, n: usize) -> Option<Vec<u32>> {
    lines
        .map(|l| {
            let mut l: Vec<u32> = l.iter().copied().filter(|&i| (i as usize) < n).collect();
            l.sort_unstable();
            l.dedup();
            l
        })
        .filter(|l| !l.is_empty())
}

/// Every `spacing`-th of the lines in use (`used`, or all `n`).
fn used(used: &Option<Vec<u32>>, n: usize, spacing: u32) -> Vec<usize> {
    let s = spacing.max(1) as usize;
    match used {
        Some(l) => l.iter().map(|&i| i as usize).step_by(s).collect(),
        None => (0..n).step_by(s).collect(),
    }
}

/// The spacing of the `used` lines around `x`.
fn span(lines: &[f32], used: &[usize], x: f32) -> f32 {
    let used: Vec<f32> = used.iter().filter_map(|&i| lines.get(i).copied()).collect();
    if used.len() < 2 {
        return 0.0;
    }
    let j = used.partition_point(|&l| l <= x).clamp(1, used.len() - 1);
    used[j] - used[j - 1]
}

/// `azimuth` moved by whole turns to lie nearest the middle of `lines`, so
/// an eye "before" the first line clamps to it rather than to the last.
fn unwrap_around(lines: &[f32], azimuth: f32) -> f32 {
    let (Some(first), Some(last)) = (lines.first(), lines.last()) else {
        return azimuth;
    };
    let middle = 0.5 * (first + last);
    middle + (azimuth - middle + 180.0).rem_euclid(360.0) - 180.0
}

/// The `used` lines (indices into `lines`, increasing) around `x` and
/// the fraction of the way from the lower to the upper one; clamped at
/// the used ends; NaN counts as the start.
fn bracket(lines: &[f32], used: &[usize], x: f32) -> (u32, u32, f32) {
    let used: Vec<usize> = used.iter().copied().filter(|&i| i < lines.len()).collect();
    let (Some(&first), Some(&last)) = (used.first(), used.last()) else {
        return (0, 0, 0.0);
    };
    if !x.is_finite() || x <= lines[first] || used.len() == 1 {
        return (first as u32, first as u32, 0.0);
    }
    if x >= lines[last] {
        return (last as u32, last as u32, 0.0);
    }
    let j = used.partition_point(|&i| lines[i] <= x).saturating_sub(1);
    let (lo, hi) = (used[j], used[(j + 1).min(used.len() - 1)]);
    let span = lines[hi] - lines[lo];
    let t = if span > 0.0 {
        (x - lines[lo]) / span
    } else {
        0.0
    };
    (lo as u32, hi as u32, t.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orbit_grid() -> ViewGrid {
        ViewGrid {
            azimuths_deg: (0..100).map(|k| k as f32).collect(),
            elevations_deg: vec![0.0],
            azimuths_used: None,
            elevations_used: None,
            ring_line_every: 1,
        }
    }

    #[test]
    fn on_a_sample_draws_it_alone_between_two_blends_by_distance() {
        let g = orbit_grid();
        for k in [0, 1, 37, 99] {
            assert_eq!(g.blend(k as f32, 0.0, 1, true), SampleBlend::one(k));
        }
        let b = g.blend(10.25, 0.0, 1, true);
        assert_eq!(b.indices().collect::<Vec<_>>(), [10, 11]);
        assert!((b.samples[1].1 - 0.25).abs() < 1e-4, "{b:?}");
        let b = g.blend(10.75, 0.0, 1, true);
        assert_eq!(b.first(), 11);
        assert_eq!(g.blend(10.75, 0.0, 1, false), SampleBlend::one(11));
        // Elevation off a one-row grid keeps the azimuth's blend.
        assert_eq!(g.blend(42.5, 30.0, 1, true).samples.len(), 2);
    }

    #[test]
    fn a_2d_cell_blends_its_four_corners_bilinearly() {
        let g = ViewGrid {
            azimuths_deg: vec![0.0, 4.0, 10.0],
            elevations_deg: vec![0.0, 15.0, 30.0],
            azimuths_used: None,
            elevations_used: None,
            ring_line_every: 1,
        };
        assert_eq!(g.len(), 9);
        assert_eq!(g.coords(5), (2, 1));
        assert_eq!(g.angles(5), (10.0, 15.0));
        let b = g.blend(7.0, 22.5, 1, true);
        assert_eq!(b.samples.len(), 4);
        let w = |k| b.samples.iter().find(|s| s.0 == k).map_or(0.0, |s| s.1);
        // Half way in both: 0.25 each corner of cell (1..2) × (1..2).
        for k in [g.index(1, 1), g.index(2, 1), g.index(1, 2), g.index(2, 2)] {
            assert!((w(k) - 0.25).abs() < 1e-5, "{b:?}");
        }
        let sum: f32 = b.samples.iter().map(|s| s.1).sum();
        assert!((sum - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_subset_of_rings_blends_across_the_rings_left_out() {
        let g = ViewGrid {
            azimuths_deg: vec![0.0, 4.0],
            elevations_deg: vec![0.0, 5.0, 10.0, 15.0, 20.0],
            azimuths_used: None,
            elevations_used: None,
            ring_line_every: 1,
        }
        .with_elevations_used(Some(&[4, 0, 9]));
        assert_eq!(g.elevations_used, Some(vec![0, 4]));
        // On azimuth line 1 at 5°: a quarter of the way from ring 0 to 4.
        let b = g.blend(4.0, 5.0, 1, true);
        let w = |k| b.samples.iter().find(|s| s.0 == k).map_or(0.0, |s| s.1);
        assert!((w(g.index(1, 0)) - 0.75).abs() < 1e-5, "{b:?}");
        assert!((w(g.index(1, 4)) - 0.25).abs() < 1e-5, "{b:?}");
        assert_eq!(b.samples.len(), 2);
        assert_eq!(g.cell_size(4.0, 5.0, 1).1, 20.0);
        // Every ring again.
        let all = g.with_elevations_used(None);
        assert_eq!(
            all.blend(4.0, 5.0, 1, true),
            SampleBlend::one(all.index(1, 1))
        );
    }

    #[test]
    fn sparse_upper_rings_number_their_own_lines_and_blend_among_them() {
        // 9 lines 1° apart; rings at 0° and 10° keep every 4th (and the
        // last): lines 0, 4, 8 → samples 9, 10, 11.
        let g = ViewGrid {
            azimuths_deg: (0..9).map(|k| k as f32).collect(),
            elevations_deg: vec![0.0, 10.0],
            ring_line_every: 4,
            ..Default::default()
        };
        assert_eq!(g.len(), 12);
        assert_eq!(
            (g.coords(3), g.coords(10), g.coords(11)),
            ((3, 0), (4, 1), (8, 1))
        );
        for k in 0..g.len() {
            let (a, e) = g.coords(k);
            assert_eq!(g.index(a, e), k, "{k}");
        }
        // On the upper ring between its lines 4 and 8: 3/4 of the way.
        let b = g.blend(7.0, 10.0, 1, true);
        assert_eq!(b.indices().collect::<Vec<_>>(), [11, 10]);
        assert!((b.samples[0].1 - 0.75).abs() < 1e-5, "{b:?}");
        // Half way up at 7°: the first ring's 7 alone, the upper ring's two.
        let b = g.blend(7.0, 5.0, 1, true);
        let w = |k| b.samples.iter().find(|s| s.0 == k).map_or(0.0, |s| s.1);
        assert!(
            (w(7) - 0.5).abs() < 1e-5 && (w(11) - 0.375).abs() < 1e-5,
            "{b:?}"
        );
        assert!((w(10) - 0.125).abs() < 1e-5, "{b:?}");
        assert_eq!(g.cell_size(7.0, 10.0, 1), (4.0, 10.0));
        assert_eq!(g.cell_size(7.0, 0.0, 1).0, 1.0);
        assert_eq!(g.blend(2.0, 0.0, 1, true), SampleBlend::one(2));
    }

    #[test]
    fn views_beyond_the_grid_clamp_and_bad_input_stays_in_range() {
        let g = orbit_grid();
        for (az, k) in [(-5.0, 0), (-100.0, 0), (140.0, 99), (200.0, 99)] {
            assert_eq!(g.blend(az, 0.0, 1, true), SampleBlend::one(k), "{az}");
        }
        for (az, el) in [
            (f32::NAN, 0.0),
            (0.0, f32::NAN),
            (f32::INFINITY, f32::NEG_INFINITY),
        ] {
            let b = g.blend(az, el, 1, true);
            assert!(b.indices().all(|k| k < g.len()), "{b:?}");
        }
        let single = ViewGrid {
            azimuths_deg: vec![5.0],
            elevations_deg: vec![0.0],
            azimuths_used: None,
            elevations_used: None,
            ring_line_every: 1,
        };
        assert_eq!(single.blend(50.0, 3.0, 1, true), SampleBlend::one(0));
    }

    #[test]
    fn spacing_uses_every_nth_line() {
        let g = orbit_grid();
        let b = g.blend(13.0, 0.0, 4, true);
        assert_eq!(b.indices().collect::<Vec<_>>(), [12, 16]);
        assert!((b.samples[1].1 - 0.25).abs() < 1e-4);
        // The last used line is 96: 99 clamps to it.
        assert_eq!(g.blend(99.0, 0.0, 4, true), SampleBlend::one(96));
        assert_eq!(g.cell_size(13.0, 0.0, 4), (4.0, 0.0));
        assert_eq!(g.cell_size(-20.0, 0.0, 1), (1.0, 0.0));
    }

    #[test]
    fn a_subset_of_lines_blends_between_its_neighbours_with_indices_kept() {
        let g = orbit_grid().with_azimuths_used(Some(&[90, 10, 0, 16, 10, 500]));
        assert_eq!(g.azimuths_used.as_deref(), Some(&[0, 10, 16, 90][..]));
        let b = g.blend(13.0, 0.0, 1, true);
        assert_eq!(b.indices().collect::<Vec<_>>(), [10, 16]);
        assert!((b.samples[0].1 - 0.5).abs() < 1e-4, "{b:?}");
        // On a used line alone; on an unused one, blended; clamped at the
        // used ends, not the grid's.
        assert_eq!(g.blend(16.0, 0.0, 1, true), SampleBlend::one(16));
        assert_eq!(g.blend(5.0, 0.0, 1, true).samples.len(), 2);
        assert_eq!(g.blend(99.0, 0.0, 1, true), SampleBlend::one(90));
        assert_eq!(g.cell_size(40.0, 0.0, 1), (74.0, 0.0));
        // Spacing counts used lines; no subset means every line.
        assert_eq!(
            g.blend(8.0, 0.0, 2, true).indices().collect::<Vec<_>>(),
            [0, 16]
        );
        assert_eq!(g.blend(50.0, 0.0, 2, true), SampleBlend::one(16));
        let all = orbit_grid().with_azimuths_used(Some(&[]));
        assert_eq!(all, orbit_grid());
        for az in [f32::NAN, -3.0, 1e9] {
            assert!(
                g.blend(az, 0.0, 1, true)
                    .indices()
                    .all(|k| [0, 10, 16, 90].contains(&k))
            );
        }
    }
}
