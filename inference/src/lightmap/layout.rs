//! Each diffuse object's light-map texture: which part of each chart is
//! stored, at how many texels per metre, and where it sits in the texture.
//!
//! The thesis's rule (papers.md §1, thesis 3.2): an affine map per chart,
//! resolution such that the texture→screen Jacobian's largest singular
//! value stays ≤ `jacobian` wherever the views see it, power-of-two sizes,
//! only the used part stored. The light map holds the light alone (the
//! albedo texture it multiplies keeps the surface's detail at its own
//! resolution), so the rule is applied to it with `magnification` more
//! pixels per texel (measured: engine/NOTES-room.md). Seen charts are laid
//! side by side along x with a gutter, each cropped to what the views see
//! plus a margin; the slack of the power-of-two rounding goes to every
//! chart as extra resolution, never to unused texels.

use super::survey::ObjectSight;
use glam::Vec2;
use serde::{Deserialize, Serialize};

/// The resolution rule's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    /// Largest texel→pixel magnification allowed for a texture carrying the
    /// surface's whole appearance (thesis: 1.25).
    pub jacobian: f32,
    /// Extra magnification a light map may have over `jacobian`.
    pub magnification: f32,
    /// Texture size bounds per side (powers of two).
    pub min_size: u32,
    pub max_size: u32,
    /// Texels kept around each chart's rectangle at the finest level.
    pub gutter: u32,
    /// Metres added around what the views see of a chart.
    pub margin_m: f32,
}

impl Default for Rule {
    fn default() -> Self {
        Self {
            jacobian: 1.25,
            magnification: 16.0,
            min_size: 4,
            max_size: 2048,
            gutter: 2,
            margin_m: 0.25,
        }
    }
}

/// Where one chart's stored part sits in its object's texture.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// The stored part's low corner in chart coordinates (metres).
    pub chart_lo: [f32; 2],
    /// Where that corner lands in the texture, texels.
    pub texel_origin: [f32; 2],
    /// Texels per metre along the chart's two axes.
    pub texels_per_metre: [f32; 2],
}

/// One diffuse object's light map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectLightmap {
    pub object: String,
    pub width: u32,
    pub height: u32,
    /// Per chart of the object (see `charts`): None where no view sees it.
    pub placements: Vec<Option<Placement>>,
    /// What the rule asks of a texture holding the whole appearance:
    /// texels per metre, the largest over the object's charts.
    pub rule_texels_per_metre: f32,
}

impl ObjectLightmap {
    /// Texture coordinates of every vertex: its chart's placement, or the
    /// texture's centre for a chart no view sees (drawn, never inferred).
    pub fn uvs(&self, charts: &super::Charts) -> Vec<Vec2> {
        let size = Vec2::new(self.width as f32, self.height as f32);
        charts
            .coords
            .iter()
            .zip(&charts.vertex_chart)
            .map(
                |(c, &k)| match self.placements.get(k as usize).copied().flatten() {
                    Some(p) => {
                        let texel = Vec2::from(p.texel_origin)
                            + (*c - Vec2::from(p.chart_lo)) * Vec2::from(p.texels_per_metre);
                        texel / size
                    }
                    None => Vec2::splat(0.5),
                },
            )
            .collect()
    }

    pub fn texels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

/// The light map of `sight`'s object under `rule`; None when no view sees it.
pub fn plan(name: &str, sight: &ObjectSight, rule: &Rule) -> Option<ObjectLightmap> {
    // Per seen chart: the stored part (metres) and its texels per metre.
    let parts: Vec<Option<(Vec2, Vec2, f32)>> = sight
        .sights
        .iter()
        .zip(&sight.charts.extents)
        .map(|(s, extent)| {
            s.map(|s| {
                let lo = (s.lo - rule.margin_m).max(Vec2::ZERO);
                let hi = (s.hi + rule.margin_m).min(*extent).max(lo + 1e-3);
                (lo, hi - lo, s.pixels_per_metre / rule.jacobian)
            })
        })
        .collect();
    let rule_density = parts.iter().flatten().map(|p| p.2).fold(0.0, f32::max);
    if parts.iter().all(Option::is_none) {
        return None;
    }
    let light = |d: f32| (d / rule.magnification).max(1e-3);
    let gutters = 2 * rule.gutter;
    let want_w: f32 = parts
        .iter()
        .flatten()
        .map(|p| p.1.x * light(p.2) + gutters as f32)
        .sum();
    let want_h = parts
        .iter()
        .flatten()
        .map(|p| p.1.y * light(p.2) + gutters as f32)
        .fold(0.0, f32::max);
    let size = |want: f32| {
        (want.ceil().max(1.0) as u32)
            .next_power_of_two()
            .clamp(rule.min_size, rule.max_size)
    };
    let (width, height) = (size(want_w), size(want_h));
    // Every chart's x share grows (or shrinks, at max_size) by one factor;
    // each chart's height fills the texture.
    let seen = parts.iter().flatten().count() as u32;
    let content_w: f32 = parts.iter().flatten().map(|p| p.1.x * light(p.2)).sum();
    let scale_x = (width.saturating_sub(seen * gutters)).max(seen) as f32 / content_w.max(1e-6);
    let inner_h = height.saturating_sub(gutters).max(1) as f32;
    let mut x = rule.gutter as f32;
    let placements = parts
        .iter()
        .map(|p| {
            p.map(|(lo, size, density)| {
                let texels_per_metre = [light(density) * scale_x, inner_h / size.y];
                let placement = Placement {
                    chart_lo: lo.into(),
                    texel_origin: [x, rule.gutter as f32],
                    texels_per_metre,
                };
                x += size.x * texels_per_metre[0] + gutters as f32;
                placement
            })
        })
        .collect();
    Some(ObjectLightmap {
        object: name.into(),
        width,
        height,
        placements,
        rule_texels_per_metre: rule_density,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lightmap::survey::ChartSight;
    use crate::scene::room;
    use glam::Vec3;

    fn walls_seen(sights: [Option<ChartSight>; 4]) -> ObjectSight {
        let walls = room::walls(Vec3::new(-4.0, 0.0, -4.0), Vec3::new(4.0, 4.0, 4.0), 1.0);
        ObjectSight {
            object: 0,
            charts: crate::lightmap::charts(&walls),
            sights: sights.to_vec(),
        }
    }

    fn seen(lo: [f32; 2], hi: [f32; 2], ppm: f32) -> Option<ChartSight> {
        Some(ChartSight {
            lo: lo.into(),
            hi: hi.into(),
            pixels_per_metre: ppm,
            hits: 100,
        })
    }

    #[test]
    fn seen_charts_are_stored_side_by_side_within_the_rule() {
        let sight = walls_seen([
            seen([1.0, 0.0], [7.0, 1.0], 200.0),
            None,
            seen([0.0, 0.0], [3.0, 1.5], 100.0),
            None,
        ]);
        let rule = Rule::default();
        let map = plan("walls", &sight, &rule).expect("seen");
        assert!(map.width.is_power_of_two() && map.height.is_power_of_two());
        assert_eq!(map.rule_texels_per_metre, 160.0);
        let [a, b] = [map.placements[0].expect("a"), map.placements[2].expect("b")];
        assert!(map.placements[1].is_none() && map.placements[3].is_none());
        // Never coarser than the rule asks of a light map.
        assert!(a.texels_per_metre[0] >= 200.0 / 1.25 / rule.magnification - 1e-3);
        assert!(b.texels_per_metre[1] >= 100.0 / 1.25 / rule.magnification - 1e-3);
        // Side by side, gutters apart, inside the texture.
        let a_end = a.texel_origin[0] + (6.0 + 0.5) * a.texels_per_metre[0];
        assert!(b.texel_origin[0] >= a_end + 2.0 * rule.gutter as f32 - 1e-3);
        let b_end = b.texel_origin[0] + 3.25 * b.texels_per_metre[0];
        assert!(
            b_end <= map.width as f32 - rule.gutter as f32 + 1e-2,
            "{map:?}"
        );
        // A vertex at the stored part's corner lands on its placement.
        let uvs = map.uvs(&sight.charts);
        assert!(uvs.iter().all(|uv| uv.is_finite()));
        assert!(plan("walls", &walls_seen([None; 4]), &rule).is_none());
    }

    #[test]
    fn sizes_stay_within_the_bounds() {
        let sight = walls_seen([seen([0.0, 0.0], [8.0, 4.0], 1e6), None, None, None]);
        let map = plan("walls", &sight, &Rule::default()).expect("seen");
        assert_eq!((map.width, map.height), (2048, 2048));
        // A chart needing under a texel: the smallest texture there is, or
        // the smallest holding its gutters (2 + 2 texels around one texel).
        let tiny = walls_seen([seen([0.0, 0.0], [0.01, 0.01], 1e-3), None, None, None]);
        let bare = Rule {
            gutter: 0,
            ..Rule::default()
        };
        let map = plan("walls", &tiny, &bare).expect("seen");
        assert_eq!((map.width, map.height), (4, 4));
        let map = plan("walls", &tiny, &Rule::default()).expect("seen");
        assert_eq!((map.width, map.height), (8, 8));
    }
}
