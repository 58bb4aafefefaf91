//! The views `engine eval` scores: on the orbit (exactly on samples),
//! between samples, and above the orbit plane.

use inference::scene::Scene;

/// Where a view sits relative to the viewpoint samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    On,
    Between,
    Above,
}

#[derive(Clone, Copy, Debug)]
pub struct View {
    pub category: Category,
    pub azimuth_deg: f32,
    pub elevation_deg: f32,
}

/// `n` views per category, spread evenly along the orbit: on a sample,
/// half-way to the next, and on a sample's azimuth at each of `elevations`
/// above the plane.
pub fn views(scene: &Scene, n: u32, elevations: &[f32]) -> Vec<View> {
    let o = &scene.orbit;
    let last = o.samples.saturating_sub(1);
    let samples: Vec<u32> = (0..n)
        .map(|i| (((i as f32 + 0.5) / n as f32) * last as f32).round() as u32)
        .map(|k| k.min(last.saturating_sub(1)))
        .collect();
    let mut kinds = vec![(Category::On, 0.0, 0.0), (Category::Between, 0.5, 0.0)];
    kinds.extend(elevations.iter().map(|&e| (Category::Above, 0.0, e)));
    let mut out = Vec::new();
    for (category, offset, up) in kinds {
        for &k in &samples {
            out.push(View {
                category,
                azimuth_deg: o.between_deg(k, offset),
                elevation_deg: up,
            });
        }
    }
    out
}
