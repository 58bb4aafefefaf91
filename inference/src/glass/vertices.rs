//! What the GPU draws per vertex of a tessellated lens: its position, the
//! two terms' `F·G` weights and, per shell, the two exit rays' cube
//! lookups — one interleaved stream, built in parallel.

use glam::Vec3;
use rayon::prelude::*;

use super::shells::{MAX_SHELLS, ShellSet};
use super::tessellate::Tessellation;

/// Floats per vertex for `shells` shells: position, `F_T·G_T`, `F_R·G_R`,
/// then per shell the refraction term's lookup, then per shell the
/// reflection term's.
pub fn stride(shells: usize) -> usize {
    9 + 6 * shells
}

/// Which of the two terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Term {
    /// Starting by refraction.
    T,
    /// Starting by reflection.
    R,
}

/// Fills `out` with the stream of `tess` against `shells` (resized to
/// `positions × stride` floats).
pub fn vertex_stream(tess: &Tessellation, shells: &ShellSet, out: &mut Vec<f32>) {
    vertex_stream_padded(tess, shells, shells.shells.len(), out);
}

/// [`vertex_stream`] laid out for `slots` shells (at least as many as
/// `shells` has, at most [`MAX_SHELLS`]): the slots past the last shell
/// repeat its lookups, so one layout serves every shell count.
pub fn vertex_stream_padded(
    tess: &Tessellation,
    shells: &ShellSet,
    slots: usize,
    out: &mut Vec<f32>,
) {
    let n = shells.shells.len().min(MAX_SHELLS);
    let slots = slots.clamp(n, MAX_SHELLS);
    let stride = stride(slots);
    out.resize(tess.positions.len() * stride, 0.0);
    out.par_chunks_mut(stride)
        .zip(tess.positions.par_iter().zip(&tess.paths))
        .for_each(|(v, (p, paths))| {
            v[0..3].copy_from_slice(&p.to_array());
            v[3..6].copy_from_slice(&paths.t.weight.to_array());
            v[6..9].copy_from_slice(&paths.r.weight.to_array());
            let mut looks = [Vec3::ZERO; MAX_SHELLS];
            for (k, path) in [&paths.t, &paths.r].into_iter().enumerate() {
                shells.lookups(path.origin, path.dir, &mut looks[..n]);
                for i in 0..slots {
                    let at = 9 + 3 * (k * slots + i);
                    v[at..at + 3].copy_from_slice(&looks[i.min(n.saturating_sub(1))].to_array());
                }
            }
        });
}

/// Every vertex's lookup into shell `shell` for `term` (the probe renders').
pub fn term_lookups(tess: &Tessellation, shells: &ShellSet, term: Term, shell: usize) -> Vec<Vec3> {
    let origin = shells.origin();
    let Some(s) = shells.shells.get(shell) else {
        return vec![Vec3::Z; tess.positions.len()];
    };
    tess.paths
        .par_iter()
        .map(|paths| {
            let path = match term {
                Term::T => &paths.t,
                Term::R => &paths.r,
            };
            s.shape.lookup(origin, path.origin, path.dir)
        })
        .collect()
}
