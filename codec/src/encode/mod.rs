//! The encoder: blocks → adaptive pyramids → DCT images → R-D curves →
//! rate allocation → container.

mod analyse;
mod blocks;
mod fit;

pub use crate::rate::Weighting;

use std::io::Write;
use std::path::Path;

use rayon::prelude::*;

use crate::container::{TextureInfo, block_table_bytes, header_bytes};
use crate::error::{CodecError, Result};
use crate::input::{EncodeInput, TextureId};
use crate::rate::{AtomRd, TexWeight};
use analyse::{BlockJob, analyse_block};
use blocks::texture_infos;
use fit::fit_budget;

/// How big the container should be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Raw size (32-bit floats, all MIPs) divided by this.
    Ratio(f64),
    /// Total container bytes.
    Bytes(u64),
}

#[derive(Clone, Debug)]
pub struct EncodeOptions {
    /// Exponent `g` of the gamma compensation (coding domain x^(1/g)).
    pub gamma: f32,
    /// The α of the `MSE_i ≤ α · mean MSE` cap; `f64::INFINITY` disables it.
    pub alpha_cap: f64,
    /// Stagger block origins per object (thesis §4.7).
    pub stagger: bool,
    /// Quantiser steps tried per image (half an octave apart).
    pub rd_points: usize,
    /// What the rate allocation minimises.
    pub weighting: Weighting,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        Self {
            gamma: 2.0,
            alpha_cap: 1.25,
            weighting: Weighting::Screen,
            stagger: true,
            rd_points: 24,
        }
    }
}

/// What the encoder did, per texture.
#[derive(Clone, Debug)]
pub struct TextureReport {
    pub id: TextureId,
    /// Coding-domain MSE per element predicted by the R-D curves.
    pub predicted_mse: f64,
    pub blocks: usize,
    /// Pyramid plans chosen (exponents per level) for each block.
    pub plans: Vec<Vec<[u8; 2]>>,
}

#[derive(Clone, Debug)]
pub struct EncodeReport {
    pub bytes: u64,
    pub raw_bytes: u64,
    pub ratio: f64,
    pub budget_bytes: u64,
    pub lambda: f64,
    pub textures: Vec<TextureReport>,
}

/// Encodes a scene's textures into a container held in memory.
pub fn encode(
    input: &EncodeInput,
    target: Target,
    opts: &EncodeOptions,
) -> Result<(Vec<u8>, EncodeReport)> {
    let mut all = encode_targets(input, &[target], opts)?;
    Ok(all.remove(0))
}

/// [`encode`] at several targets, analysing the input (pyramids, DCT,
/// rate/distortion curves — nearly all of the work) once: each result is
/// the container [`encode`] gives for that target alone.
pub fn encode_targets(
    input: &EncodeInput,
    targets: &[Target],
    opts: &EncodeOptions,
) -> Result<Vec<(Vec<u8>, EncodeReport)>> {
    input.validate()?;
    check_options(opts, targets)?;
    let raw = input.raw_bytes();
    let budgets = targets
        .iter()
        .map(|&target| match target {
            Target::Ratio(r) if r.is_finite() && r > 0.0 => Ok((raw as f64 / r).floor() as u64),
            Target::Bytes(b) if b > 0 => Ok(b),
            other => Err(CodecError::BadRequest(format!("invalid target {other:?}"))),
        })
        .collect::<Result<Vec<u64>>>()?;
    let infos = texture_infos(input, opts);
    let jobs = analyse_blocks(input, &infos, opts);
    let fixed: u64 = header_bytes(infos.len(), jobs.len())
        + jobs
            .iter()
            .map(|j| block_table_bytes(&infos[j.tex], &j.plan))
            .sum::<u64>();
    if let Some(&budget) = budgets.iter().find(|&&b| b < fixed) {
        return Err(CodecError::BudgetTooSmall {
            budget,
            minimum: fixed,
        });
    }
    let weights = texture_weights(input, opts);
    let rds: Vec<AtomRd> = jobs
        .iter()
        .flat_map(|j| j.atoms.iter().map(|a| a.rd.clone()))
        .collect();
    budgets
        .iter()
        .map(|&budget| fit_budget(&jobs, &infos, &rds, &weights, raw, budget, fixed, opts))
        .collect()
}

fn check_options(opts: &EncodeOptions, targets: &[Target]) -> Result<()> {
    if !(opts.gamma.is_finite() && (1.0..=4.0).contains(&opts.gamma)) {
        return Err(CodecError::BadRequest(format!(
            "gamma {} outside 1..=4",
            opts.gamma
        )));
    }
    if opts.alpha_cap.is_nan() || opts.alpha_cap < 1.0 {
        return Err(CodecError::BadRequest(format!(
            "alpha_cap {} below 1",
            opts.alpha_cap
        )));
    }
    if targets.is_empty() {
        return Err(CodecError::BadRequest("no target".into()));
    }
    Ok(())
}

/// Every block of every texture analysed, in container order.
fn analyse_blocks(
    input: &EncodeInput,
    infos: &[TextureInfo],
    opts: &EncodeOptions,
) -> Vec<BlockJob> {
    let mut jobs_spec = Vec::new();
    for (ti, info) in infos.iter().enumerate() {
        for b1 in 0..info.blocks[1] {
            for b0 in 0..info.blocks[0] {
                jobs_spec.push((ti, [b0, b1]));
            }
        }
    }
    jobs_spec
        .par_iter()
        .map(|&(ti, b)| analyse_block(&input.textures[ti], &infos[ti], b, ti, opts))
        .collect()
}

/// Each texture's weight in the rate allocation.
fn texture_weights(input: &EncodeInput, opts: &EncodeOptions) -> Vec<TexWeight> {
    let mean_area = input
        .textures
        .iter()
        .map(|t| t.screen_area as f64)
        .sum::<f64>()
        / input.textures.len() as f64;
    input
        .textures
        .iter()
        .map(|t| TexWeight {
            // A texture with no area still gets a token weight, not nothing.
            area: if opts.weighting == Weighting::Texels {
                1.0
            } else if mean_area > 0.0 {
                (t.screen_area as f64).max(1e-3 * mean_area)
            } else {
                1.0
            },
            elements: match opts.weighting {
                Weighting::Screen => t.data.len() as f64,
                Weighting::Texels => 1.0,
            },
        })
        .collect()
}

/// Encodes and writes the container atomically: a temporary file in the
/// same directory, synced, then renamed over `path`.
pub fn encode_to_file(
    input: &EncodeInput,
    target: Target,
    opts: &EncodeOptions,
    path: &Path,
) -> Result<EncodeReport> {
    let (bytes, report) = encode(input, target, opts)?;
    write_atomic(path, &bytes)?;
    Ok(report)
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |cause| CodecError::Io {
        path: path.display().to_string(),
        cause,
    };
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}
