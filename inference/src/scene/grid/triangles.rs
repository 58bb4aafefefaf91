//! A view between two rings blended from three samples instead of four:
//! the strip between the rings is cut into triangles whose corners are the
//! rings' samples (a ribbon: each step joins the next line of one ring to
//! the current line of the other, the shorter diagonal first), and the view
//! takes the barycentric weights of the triangle that holds it — the rule
//! reflection-space IBR uses on its sphere of views (seed 003). The weights
//! are piecewise linear and continuous, equal the rings' own 1D blend on
//! the rings, and cost the composite one cube lookup per layer less than
//! the cell's four corners.

use super::{SampleBlend, ViewGrid, bracket, unwrap_around};

/// How a view between rings weighs the samples around it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ViewBlend {
    /// The four corners of its grid cell, bilinearly (PEM paper §5).
    Bilinear,
    /// The three corners of the triangle of rings' samples that holds it.
    #[default]
    Triangles,
}

impl ViewBlend {
    pub const ALL: [ViewBlend; 2] = [ViewBlend::Bilinear, ViewBlend::Triangles];

    pub fn name(self) -> &'static str {
        match self {
            ViewBlend::Bilinear => "bilinear",
            ViewBlend::Triangles => "triangles",
        }
    }
}

impl std::str::FromStr for ViewBlend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| format!("{s:?}: expected `bilinear` or `triangles`"))
    }
}

/// A triangle corner: (on the upper ring, index into that ring's lines).
type Corner = (bool, usize);

impl ViewGrid {
    /// The samples a view at (`azimuth`, `elevation`) draws under `rule`,
    /// every `spacing`-th line; with `blend` false the nearest alone. Views
    /// on one ring, beyond the grid or outside the strip's triangles (rings
    /// whose lines end at different azimuths) take the bilinear weights.
    pub fn blend_by(
        &self,
        azimuth: f32,
        elevation: f32,
        spacing: u32,
        blend: bool,
        rule: ViewBlend,
    ) -> SampleBlend {
        let bilinear = || self.blend(azimuth, elevation, spacing, blend);
        if rule == ViewBlend::Bilinear || !blend {
            return bilinear();
        }
        let az = unwrap_around(&self.azimuths_deg, azimuth);
        let (e0, e1, te) = bracket(
            &self.elevations_deg,
            &self.elevation_lines(spacing),
            elevation,
        );
        if e0 == e1 || te <= 0.0 || te >= 1.0 || !az.is_finite() {
            return bilinear();
        }
        let rows = [e0, e1].map(|e| self.azimuth_lines(spacing, e));
        // A ring with no line in use (a subset of lines that skips all of
        // a sparse ring's) has no triangles.
        if rows.iter().any(|r| r.is_empty()) {
            return bilinear();
        }
        let angles = rows.each_ref().map(|r| {
            r.iter()
                .map(|&i| self.azimuths_deg[i])
                .collect::<Vec<f32>>()
        });
        let Some(corners) = ribbon_weights(&angles[0], &angles[1], az, te) else {
            return bilinear();
        };
        let samples = corners
            .iter()
            .map(|&((upper, i), w)| {
                let ring = usize::from(upper);
                (self.index(rows[ring][i] as u32, [e0, e1][ring]), w)
            })
            .collect();
        SampleBlend::normalized(samples, true, self.index(rows[0][0] as u32, e0))
    }
}

/// The triangle of the ribbon between a lower ring's line azimuths
/// (`lower`, at height 0) and an upper ring's (`upper`, at height 1)
/// that holds (`x`, `t`), with its corners' barycentric weights; None
/// outside every triangle.
fn ribbon_weights(lower: &[f32], upper: &[f32], x: f32, t: f32) -> Option<[(Corner, f32); 3]> {
    let (mut i, mut j) = (0, 0);
    let at = |(up, k): Corner| -> (f32, f32) { if up { (upper[k], 1.0) } else { (lower[k], 0.0) } };
    while i + 1 < lower.len() || j + 1 < upper.len() {
        let step_lower = if i + 1 == lower.len() {
            false
        } else if j + 1 == upper.len() {
            true
        } else {
            (lower[i + 1] - upper[j]).abs() <= (upper[j + 1] - lower[i]).abs()
        };
        let tri: [Corner; 3] = if step_lower {
            i += 1;
            [(false, i - 1), (false, i), (true, j)]
        } else {
            j += 1;
            [(false, i), (true, j - 1), (true, j)]
        };
        if let Some(w) = barycentric(tri.map(at), (x, t)) {
            return Some([(tri[0], w[0]), (tri[1], w[1]), (tri[2], w[2])]);
        }
    }
    None
}

/// The barycentric weights of `p` in triangle `v` (clamped to ≥ 0), or
/// None when `p` lies outside it or the triangle is degenerate.
fn barycentric(v: [(f32, f32); 3], p: (f32, f32)) -> Option<[f32; 3]> {
    const SLACK: f32 = 1e-5;
    let [(ax, ay), (bx, by), (cx, cy)] = v;
    let det = (by - cy) * (ax - cx) + (cx - bx) * (ay - cy);
    if det.abs() < 1e-12 {
        return None;
    }
    let wa = ((by - cy) * (p.0 - cx) + (cx - bx) * (p.1 - cy)) / det;
    let wb = ((cy - ay) * (p.0 - cx) + (ax - cx) * (p.1 - cy)) / det;
    let wc = 1.0 - wa - wb;
    if wa < -SLACK || wb < -SLACK || wc < -SLACK {
        return None;
    }
    Some([wa.max(0.0), wb.max(0.0), wc.max(0.0)])
}

#[cfg(test)]
mod tests;
