//! What `engine place` may spend besides samples: container bytes or
//! compile minutes, each turned into samples at the dense compile's cost
//! per sample (the codec codes at a fixed ratio and a sample's trace and
//! maps take about the same time, so both grow with the samples).

use super::grid::GridOptions;
use super::plan::{self, PlanOptions};
use crate::renderer::Renderer;
use anyhow::{Context, Result, bail};
use inference::scene::Scene;

/// What a budget counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    Bytes,
    Minutes,
}

impl Cost {
    fn option(self) -> &'static str {
        match self {
            Cost::Bytes => "--max-bytes",
            Cost::Minutes => "--max-minutes",
        }
    }
}

/// A budget and what it buys.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Budget {
    #[serde(skip)]
    pub cost: Cost,
    pub max: f64,
    /// The dense compile's cost per sample.
    pub per_sample: f64,
    /// Samples that fit.
    pub samples: u32,
}

impl Budget {
    /// None without the option; an error when the dense compile has no
    /// such cost to divide (maps from EXR files: no container; no records).
    pub fn of(
        cost: Cost,
        max: Option<f64>,
        renderer: &Renderer,
        scene: &Scene,
    ) -> Result<Option<Budget>> {
        let Some(max) = max else { return Ok(None) };
        let name = cost.option();
        let dense = match cost {
            Cost::Bytes => renderer.map_bytes.map(|b| b as f64),
            Cost::Minutes => renderer.map_compile_minutes,
        };
        let Some(dense) = dense.filter(|d| *d > 0.0) else {
            bail!(
                "{name} {max}: {}'s dense maps {}, so there is no cost per sample to budget with; \
                 use --max-samples",
                scene.name,
                match cost {
                    Cost::Bytes =>
                        "play from EXR files, not a container (encode them first: `engine encode`)",
                    Cost::Minutes => "carry no compile records",
                }
            );
        };
        let n = scene.orbit.sample_count();
        let samples = match cost {
            Cost::Bytes => plan::samples_within_bytes(max as u64, dense as u64, n),
            Cost::Minutes => (max * f64::from(n) / dense)
                .floor()
                .min(f64::from(u32::MAX)) as u32,
        };
        Ok(Some(Budget {
            cost,
            max,
            per_sample: dense / f64::from(n.max(1)),
            samples,
        }))
    }

    /// What `samples` cost at the dense cost per sample.
    pub fn estimate(&self, samples: u32) -> f64 {
        self.per_sample * f64::from(samples)
    }

    /// Caps `plan`'s budget at the lines (of `per_line` samples each) that
    /// fit; an error naming what fits when that is below the start lines.
    pub fn limit(&self, plan: &mut PlanOptions, per_line: u32) -> Result<()> {
        let per_line = per_line.max(1);
        plan.max_samples = plan.max_samples.min(self.samples / per_line);
        plan.validate().with_context(|| self.explain(per_line))
    }

    /// The same for a grid placement, whose budget counts samples.
    pub fn limit_grid(&self, grid: &mut GridOptions) -> Result<()> {
        grid.max_samples = grid.max_samples.min(self.samples);
        grid.validate().with_context(|| self.explain(1))
    }

    /// What the budget buys, in words.
    fn explain(&self, per_line: u32) -> String {
        let fit = match self.samples {
            1 => "1 sample".to_string(),
            n => format!("{n} samples"),
        };
        let rings = match per_line {
            1 => String::new(),
            n => format!(" ({} rings of {n})", self.samples / n),
        };
        let cost = match self.cost {
            Cost::Bytes => format!(
                "the dense container holds {:.0} B a sample",
                self.per_sample
            ),
            Cost::Minutes => {
                format!("the dense compile took {:.2} min a sample", self.per_sample)
            }
        };
        format!(
            "{} {}: {cost}, so {fit}{rings} fit",
            self.cost.option(),
            self.max
        )
    }
}
