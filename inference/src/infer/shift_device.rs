//! A fake probe device for the solvers' tests: view `offset` (the
//! geometry's key) shows texels offset..offset+8 of a 16-wide texture row,
//! one texel per pixel (magnified exactly: pixel centre = texel centre).

use crate::probe::{Lookup, ProbeError, ProbeGeometry, ProbeRenderer};
use crate::solve::layout::TextureLayout;

pub(super) struct ShiftDevice;

impl ProbeRenderer for ShiftDevice {
    fn render(
        &mut self,
        g: &ProbeGeometry,
        l: &TextureLayout,
        t: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, ProbeError> {
        let offset = g.key as u32;
        Ok((0..g.width * g.height)
            .map(|p| {
                let (x, y) = (p % g.width, p / g.width);
                let v = t[l.index(0, 0, x + offset, y)];
                [v[0], v[1], v[2], 1.0]
            })
            .collect())
    }
}

/// The 8×4 view at `offset`.
pub(super) fn shifted_view(offset: u64) -> ProbeGeometry {
    ProbeGeometry {
        key: offset,
        positions: vec![],
        indices: vec![],
        lookup: Lookup::Uv(vec![]),
        view_proj: glam::Mat4::IDENTITY,
        width: 8,
        height: 4,
    }
}
