//! Fitting a budget: allocating quantiser steps across the analysed
//! blocks, writing the container and shrinking until it fits.

use rayon::prelude::*;

use super::analyse::BlockJob;
use super::{EncodeOptions, EncodeReport, TextureReport};
use crate::coefs::{Contexts, encode_image, step_of};
use crate::container::{self, BlockView, TextureInfo};
use crate::entropy::Writer;
use crate::error::{CodecError, Result};
use crate::rate::{AtomRd, TexWeight, allocate};

/// Writes one block with the chosen quantiser steps.
fn write_block(job: &BlockJob, choice: &[usize], info: &TextureInfo) -> Result<Vec<u8>> {
    let mips = info.layout.mips as usize;
    let n_streams = info.stream_count(&job.plan);
    let streams: Vec<(Vec<u8>, Vec<u8>)> = (0..n_streams)
        .into_par_iter()
        .map(|s| {
            let atoms = &job.atoms[s * mips..(s + 1) * mips];
            let steps: Vec<u8> = atoms
                .iter()
                .zip(&choice[s * mips..(s + 1) * mips])
                .map(|(a, &c)| a.rd.points[c].idx)
                .collect();
            if steps.iter().all(|&i| i == 0) {
                return Ok((steps, Vec::new()));
            }
            let mut w = Writer::default();
            let mut ctx = Contexts::default();
            for (a, &idx) in atoms.iter().zip(&steps) {
                if let (Some(img), true) = (&a.img, idx != 0) {
                    encode_image(&mut w, &mut ctx, img, step_of(idx));
                }
            }
            let bytes = w
                .finish()
                .ok_or_else(|| CodecError::BadRequest("range encoder failed".into()))?;
            Ok((steps, bytes))
        })
        .collect::<Result<_>>()?;
    Ok(container::write_block(&job.plan, &streams))
}

/// Allocates and writes one container within `budget` bytes.
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_budget(
    jobs: &[BlockJob],
    infos: &[TextureInfo],
    rds: &[AtomRd],
    weights: &[TexWeight],
    raw: u64,
    budget: u64,
    fixed: u64,
    opts: &EncodeOptions,
) -> Result<(Vec<u8>, EncodeReport)> {
    // The curves give ideal code lengths; real streams add word rounding and
    // a flush, so shrink the bit budget until the file fits.
    let mut payload_budget = (budget - fixed) as f64 * 8.0;
    for _ in 0..8 {
        let alloc = allocate(rds, weights, payload_budget, opts.alpha_cap);
        let mut offset = 0;
        let mut blocks = Vec::with_capacity(jobs.len());
        for j in jobs {
            let n = j.atoms.len();
            blocks.push(write_block(
                j,
                &alloc.choice[offset..offset + n],
                &infos[j.tex],
            )?);
            offset += n;
        }
        let bytes = container::write(opts.gamma, infos, &blocks);
        let size = bytes.len() as u64;
        if size <= budget || payload_budget <= 0.0 {
            if size > budget {
                break;
            }
            let report = EncodeReport {
                bytes: size,
                raw_bytes: raw,
                ratio: raw as f64 / size as f64,
                budget_bytes: budget,
                lambda: alloc.lambda,
                textures: infos
                    .iter()
                    .enumerate()
                    .map(|(ti, info)| TextureReport {
                        id: info.id,
                        predicted_mse: alloc.mse[ti],
                        blocks: info.block_count(),
                        plans: jobs
                            .iter()
                            .filter(|j| j.tex == ti)
                            .map(|j| j.plan.levels.clone())
                            .collect(),
                    })
                    .collect(),
            };
            debug_assert!(validate_blocks(&bytes).is_ok());
            return Ok((bytes, report));
        }
        let over = (size - budget) as f64 * 8.0;
        payload_budget = (payload_budget - over * 1.5 - 64.0).max(0.0);
    }
    Err(CodecError::BudgetTooSmall {
        budget,
        minimum: fixed,
    })
}

/// Parses every block of a container (used by debug builds after encoding).
fn validate_blocks(bytes: &[u8]) -> Result<()> {
    let c = container::Container::from_bytes(bytes.to_vec())?;
    for t in c.textures() {
        for b in 0..t.block_count() {
            let i = t.first_block as usize + b;
            BlockView::parse(&c.block_bytes(i)?, t, i)?;
        }
    }
    Ok(())
}
