//! The views whose rows enter one map's solve (its own, and neighbouring
//! samples' with `neighbour_weight`), and the rendering matrices kept
//! between solves so each view is probed once although up to three
//! samples' solves stack it.

use super::layer::Target;
use crate::probe::{ProbeGeometry, RenderingMatrix};
use std::collections::VecDeque;
use std::sync::Arc;

/// One view of the object: its probe geometry, what the tracer saw there
/// and the weight its rows carry. `id` names the view's rendering matrix
/// in a [`MatrixCache`]: equal ids must mean equal geometry and layout.
#[derive(Clone, Copy)]
pub struct View<'a> {
    pub id: u64,
    pub geometry: &'a ProbeGeometry,
    pub target: Target<'a>,
    pub weight: f32,
    /// Per pixel of the view (row-major), a further factor on that
    /// pixel's row: how far the target there can be trusted (the glass
    /// targets' confidence). None: every row alike.
    pub pixel_weights: Option<&'a [f32]>,
}

/// A map's own view, the neighbouring views stacked beside it, and where
/// their matrices are kept.
pub struct Views<'a, 'c> {
    pub own: View<'a>,
    pub neighbours: &'a [View<'a>],
    pub cache: &'c mut MatrixCache,
}

/// Rendering matrices by view id, the least recently used dropped beyond
/// `capacity` (0 keeps none).
pub struct MatrixCache {
    entries: VecDeque<(u64, Arc<RenderingMatrix>)>,
    capacity: usize,
    hits: usize,
}

impl MatrixCache {
    pub fn new(capacity: usize) -> Self {
        Self {
            entries: VecDeque::new(),
            capacity,
            hits: 0,
        }
    }

    /// The matrix kept under `id` whose columns are `cols`, or the one
    /// `build` makes (then kept).
    pub fn get_or_build<E>(
        &mut self,
        id: u64,
        cols: usize,
        build: impl FnOnce() -> Result<RenderingMatrix, E>,
    ) -> Result<Arc<RenderingMatrix>, E> {
        if let Some(i) = self.entries.iter().position(|(k, _)| *k == id) {
            if let Some(entry) = self.entries.remove(i) {
                if entry.1.a.cols == cols {
                    self.hits += 1;
                    let m = Arc::clone(&entry.1);
                    self.entries.push_back(entry);
                    return Ok(m);
                }
            }
        }
        let m = Arc::new(build()?);
        if self.capacity > 0 {
            if self.entries.len() == self.capacity {
                self.entries.pop_front();
            }
            self.entries.push_back((id, Arc::clone(&m)));
        }
        Ok(m)
    }

    /// Matrices served from the cache so far.
    pub fn hits(&self) -> usize {
        self.hits
    }
}

#[cfg(test)]
mod tests {
    use super::MatrixCache;
    use crate::probe::RenderingMatrix;
    use crate::solve::csr::CsrMatrix;

    fn matrix(cols: usize) -> RenderingMatrix {
        RenderingMatrix {
            a: CsrMatrix::zeros(0, cols),
            pixels: Vec::new(),
            probe_renders: 1,
            corrected_rows: 0,
            rows_across_faces: 0,
        }
    }

    #[test]
    fn a_view_is_built_once_until_it_is_the_least_recently_used() {
        let mut cache = MatrixCache::new(2);
        let mut builds = 0;
        for id in [1, 2, 1, 3, 1, 2] {
            cache
                .get_or_build(id, 4, || {
                    builds += 1;
                    Ok::<_, ()>(matrix(4))
                })
                .expect("build");
        }
        // 1, 2 built; 1 hit; 3 built (drops 2); 1 hit; 2 built again.
        assert_eq!(builds, 4);
        assert_eq!(cache.hits(), 2);
    }

    #[test]
    fn a_kept_matrix_of_another_layout_is_rebuilt_and_zero_capacity_keeps_none() {
        let mut cache = MatrixCache::new(2);
        cache
            .get_or_build(7, 4, || Ok::<_, ()>(matrix(4)))
            .expect("4");
        let m = cache
            .get_or_build(7, 8, || Ok::<_, ()>(matrix(8)))
            .expect("8");
        assert_eq!(m.a.cols, 8);
        let mut none = MatrixCache::new(0);
        none.get_or_build(7, 4, || Ok::<_, ()>(matrix(4)))
            .expect("4");
        none.get_or_build(7, 4, || Ok::<_, ()>(matrix(4)))
            .expect("4");
        assert_eq!(none.hits(), 0);
    }
}
