//! What a scene's maps cost to compile: the seconds recorded beside each
//! file the container is made from (every sample's trace, the free views
//! its solves stack, every map), summed once per file. The container's
//! record adds its encode; `engine eval` reports that as a row's compile
//! minutes. Seconds are the machine's that made each file, so a compile
//! farmed over several machines sums their work.

use super::Plan;
use super::jobs::{StackedView, stacked_views_of};
use crate::maps::{MapSet, map_path, traced_stem, view_stem};
use inference::key::recorded_seconds;
use inference::trace::output::with_suffix;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The recorded work behind a container's inputs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Budget {
    /// Tracing the samples and the free views their solves stack.
    pub trace_s: f64,
    /// Inferring the maps (probe renders, assembly, solves).
    pub infer_s: f64,
    /// Input files whose records hold no time (made before times were
    /// recorded): the sum then undercounts, so [`Budget::seconds`] is None.
    pub untimed: usize,
}

impl Budget {
    /// The inputs' seconds, when every input's record holds them.
    pub fn seconds(&self) -> Option<f64> {
        (self.untimed == 0).then_some(self.trace_s + self.infer_s)
    }
}

/// The budget of the container of `set` of `plan`'s scene from the traces
/// under `trace_dir` and the maps under `infer_dir`.
pub fn inputs_budget(plan: &Plan, set: MapSet, trace_dir: &Path, infer_dir: &Path) -> Budget {
    let orbit = &plan.scene.orbit;
    let samples = orbit.sample_count();
    let mut traces: BTreeSet<PathBuf> = (0..samples)
        .map(|k| with_suffix(&traced_stem(trace_dir, k), ".exr"))
        .collect();
    // Only the maps the container holds (the set's).
    let specs = set.specs(plan.scene);
    let held = |job: &&super::Job| {
        specs
            .iter()
            .any(|s| s.object == job.object.name && s.layer == job.layer)
    };
    let mut maps = Vec::new();
    for job in plan.jobs.iter().filter(held) {
        for k in 0..samples {
            maps.push(map_path(infer_dir, k, &job.object.name, job.layer));
            let Some(stack) = job.stack() else { continue };
            for view in stacked_views_of(orbit, k, &stack) {
                if let StackedView::Free(azimuth, elevation) = view {
                    let stem = view_stem(trace_dir, azimuth, elevation);
                    traces.insert(with_suffix(&stem, ".exr"));
                }
            }
        }
    }
    let (trace_s, untimed_traces) = recorded(traces);
    let (infer_s, untimed_maps) = recorded(maps);
    Budget {
        trace_s,
        infer_s,
        untimed: untimed_traces + untimed_maps,
    }
}

/// The seconds recorded beside `files`, summed, and how many have none.
fn recorded(files: impl IntoIterator<Item = PathBuf>) -> (f64, usize) {
    files
        .into_iter()
        .fold((0.0, 0), |(s, n), f| match recorded_seconds(&f) {
            Some(t) => (s + t, n),
            None => (s, n + 1),
        })
}
