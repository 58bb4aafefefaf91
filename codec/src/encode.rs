//! The encoder: blocks → adaptive pyramids → DCT images → R-D curves →
//! rate allocation → container.

use std::io::Write;
use std::path::Path;

use rayon::prelude::*;

use crate::coefs::{CoefImage, Contexts, encode_image, idx_at_least, step_of};
use crate::container::{self, BLOCK_LOG2, BlockView, TextureInfo, block_table_bytes, header_bytes};
use crate::dct::Dct8;
use crate::domain::Gamma;
use crate::entropy::{CostMeter, Writer};
use crate::error::{CodecError, Result};
use crate::input::{EncodeInput, ParamTexture, TextureId};
use crate::planes::{image_offset, proxy, to_planar_domain};
use crate::pyramid::{self, Plan};
pub use crate::rate::Weighting;
use crate::rate::{AtomRd, RdPoint, TexWeight, allocate};

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

struct Atom {
    img: Option<CoefImage>,
    rd: AtomRd,
}

struct BlockJob {
    tex: usize,
    plan: Plan,
    /// In stream order: (level, node, face), then MIP.
    atoms: Vec<Atom>,
}

/// Staggered block origin for the `rank`-th of `n` objects.
fn stagger_for(rank: usize, n: usize, samples: u32) -> u32 {
    let b = 1usize << BLOCK_LOG2;
    if samples as usize <= b || n <= 1 {
        return 0;
    }
    ((rank * b / n.min(b)) % b) as u32
}

fn texture_infos(input: &EncodeInput, opts: &EncodeOptions) -> Vec<TextureInfo> {
    let mut objects: Vec<u32> = input.textures.iter().map(|t| t.id.object).collect();
    objects.sort();
    objects.dedup();
    let mut first = 0u32;
    input
        .textures
        .iter()
        .map(|t| {
            let rank = objects.binary_search(&t.id.object).unwrap_or(0);
            let s = |n| {
                if opts.stagger {
                    stagger_for(rank, objects.len(), n)
                } else {
                    0
                }
            };
            let stagger = [s(t.grid.n0), if t.grid.n1 > 1 { s(t.grid.n1) } else { 0 }];
            let mut info = TextureInfo {
                id: t.id,
                grid: t.grid,
                layout: t.layout,
                stagger,
                blocks: [0, 0],
                first_block: first,
                screen_area: t.screen_area,
            };
            let lb = info.log2b();
            info.blocks = [
                (t.grid.n0 + stagger[0]).div_ceil(1 << lb[0]),
                (t.grid.n1 + stagger[1]).div_ceil(1 << lb[1]),
            ];
            first += info.block_count() as u32;
            info
        })
        .collect()
}

/// Images up to this many coefficients per plane get a longer R-D sweep.
const SMALL_IMAGE: usize = 16 * 16;

fn rd_curve(img: &CoefImage, points: usize) -> Vec<RdPoint> {
    let energy = img.energy();
    let mut out = vec![RdPoint {
        idx: 0,
        bits: 0.0,
        dist: energy,
    }];
    if energy <= 0.0 {
        return out;
    }
    let hi = idx_at_least(2.0 * img.max_abs()) as i32;
    // `points` half-octave steps span 12 octaves below the largest
    // coefficient; a small image whose detail sits further below its DC
    // needs more to approach lossless at generous budgets. Its extra points
    // are cheap (encoding cost scales with the coefficients), so small
    // images get 4 more octaves and large ones keep their encode time.
    let points = if img.w * img.h <= SMALL_IMAGE {
        points + 8
    } else {
        points
    };
    for k in 0..points as i32 {
        let idx = hi - 2 * k;
        if idx < 1 {
            break;
        }
        let mut m = CostMeter::default();
        let dist = encode_image(&mut m, &mut Contexts::default(), img, step_of(idx as u8));
        out.push(RdPoint {
            idx: idx as u8,
            bits: m.bits,
            dist,
        });
        if dist <= energy * 1e-12 {
            break;
        }
    }
    out
}

/// Pyramid and R-D curves for one block of one texture.
fn analyse_block(
    t: &ParamTexture,
    info: &TextureInfo,
    b: [u32; 2],
    tex: usize,
    opts: &EncodeOptions,
) -> BlockJob {
    let lb = info.log2b();
    let (b0, b1) = (1usize << lb[0], 1usize << lb[1]);
    let gamma = Gamma(opts.gamma);
    let mut valid = vec![false; b0 * b1];
    let mut leaves = Vec::with_capacity(b0 * b1);
    for i1 in 0..b1 {
        for i0 in 0..b0 {
            let g0 = (b[0] as i64) * b0 as i64 + i0 as i64 - info.stagger[0] as i64;
            let g1 = (b[1] as i64) * b1 as i64 + i1 as i64 - info.stagger[1] as i64;
            valid[i0 + b0 * i1] =
                (0..t.grid.n0 as i64).contains(&g0) && (0..t.grid.n1 as i64).contains(&g1);
            // Padding leaves replicate the nearest real sample: zero detail.
            let c0 = g0.clamp(0, t.grid.n0 as i64 - 1) as usize;
            let c1 = g1.clamp(0, t.grid.n1 as i64 - 1) as usize;
            leaves.push(to_planar_domain(
                &t.layout,
                t.sample(c0 + t.grid.n0 as usize * c1),
                gamma,
            ));
        }
    }
    let proxies: Vec<Vec<f32>> = leaves.iter().map(|l| proxy(&t.layout, l)).collect();
    let plan = pyramid::choose_plan(&proxies, lb);
    let pyr = pyramid::build(&leaves, &plan, lb);
    drop(leaves);
    let l = &t.layout;
    let ch = l.channels as usize;
    let mut specs = Vec::new();
    for (level, nodes) in pyr.iter().enumerate() {
        for node in 0..nodes.len() {
            let mut leaves_under = 0.0;
            for i1 in 0..b1 {
                for i0 in 0..b0 {
                    if valid[i0 + b0 * i1] && plan.node_of(level, [i0, i1], lb) == node {
                        leaves_under += 1.0;
                    }
                }
            }
            for face in 0..l.faces {
                for mip in 0..l.mips {
                    specs.push((level, node, face, mip, leaves_under));
                }
            }
        }
    }
    let atoms = specs
        .into_par_iter()
        .map_init(
            Dct8::default,
            |dct, (level, node, face, mip, leaves_under)| {
                let (w, h) = l.mip_size(mip);
                let data = &pyr[level][node][image_offset(l, face, mip)..][..w * h * ch];
                let img = CoefImage::new(dct, data, w, h, ch);
                let points = if leaves_under > 0.0 {
                    rd_curve(&img, opts.rd_points)
                } else {
                    vec![RdPoint {
                        idx: 0,
                        bits: 0.0,
                        dist: 0.0,
                    }]
                };
                Atom {
                    img: (points.len() > 1).then_some(img),
                    rd: AtomRd {
                        texture: tex,
                        leaves: leaves_under,
                        points,
                    },
                }
            },
        )
        .collect();
    BlockJob { tex, plan, atoms }
}

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
    let mut jobs_spec = Vec::new();
    for (ti, info) in infos.iter().enumerate() {
        for b1 in 0..info.blocks[1] {
            for b0 in 0..info.blocks[0] {
                jobs_spec.push((ti, [b0, b1]));
            }
        }
    }
    let jobs: Vec<BlockJob> = jobs_spec
        .par_iter()
        .map(|&(ti, b)| analyse_block(&input.textures[ti], &infos[ti], b, ti, opts))
        .collect();

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
    let mean_area = input
        .textures
        .iter()
        .map(|t| t.screen_area as f64)
        .sum::<f64>()
        / input.textures.len() as f64;
    let weights: Vec<TexWeight> = input
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
        .collect();
    let rds: Vec<AtomRd> = jobs
        .iter()
        .flat_map(|j| j.atoms.iter().map(|a| a.rd.clone()))
        .collect();
    budgets
        .iter()
        .map(|&budget| fit_budget(&jobs, &infos, &rds, &weights, raw, budget, fixed, opts))
        .collect()
}

/// Allocates and writes one container within `budget` bytes.
#[allow(clippy::too_many_arguments)]
fn fit_budget(
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
    let io = |source| CodecError::Io {
        path: path.display().to_string(),
        source,
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
