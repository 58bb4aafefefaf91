//! Analysing one block: its adaptive pyramid, then each level image's DCT
//! and rate/distortion curve.

use rayon::prelude::*;

use super::EncodeOptions;
use crate::coefs::{CoefImage, Contexts, encode_image, idx_at_least, step_of};
use crate::container::TextureInfo;
use crate::dct::Dct8;
use crate::domain::Gamma;
use crate::entropy::CostMeter;
use crate::input::{LeafLayout, ParamTexture};
use crate::planes::{image_offset, proxy, to_planar_domain};
use crate::pyramid::{self, Plan};
use crate::rate::{AtomRd, RdPoint};

pub(super) struct Atom {
    pub(super) img: Option<CoefImage>,
    pub(super) rd: AtomRd,
}

pub(super) struct BlockJob {
    pub(super) tex: usize,
    pub(super) plan: Plan,
    /// In stream order: (level, node, face), then MIP.
    pub(super) atoms: Vec<Atom>,
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
pub(super) fn analyse_block(
    t: &ParamTexture,
    info: &TextureInfo,
    b: [u32; 2],
    tex: usize,
    opts: &EncodeOptions,
) -> BlockJob {
    let lb = info.log2b();
    let (valid, leaves) = block_leaves(t, info, b, Gamma(opts.gamma));
    let proxies: Vec<Vec<f32>> = leaves.iter().map(|l| proxy(&t.layout, l)).collect();
    let plan = pyramid::choose_plan(&proxies, lb);
    let pyr = pyramid::build(&leaves, &plan, lb);
    drop(leaves);
    let l = &t.layout;
    let ch = l.channels as usize;
    let atoms = atom_specs(l, &pyr, &plan, &valid, lb)
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

/// The block's leaves in the coding domain, and which of them are real
/// samples (the others pad the grid's edges).
fn block_leaves(
    t: &ParamTexture,
    info: &TextureInfo,
    b: [u32; 2],
    gamma: Gamma,
) -> (Vec<bool>, Vec<Vec<f32>>) {
    let lb = info.log2b();
    let (b0, b1) = (1usize << lb[0], 1usize << lb[1]);
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
    (valid, leaves)
}

/// One image to analyse: (level, node, face, MIP, real leaves under it),
/// in stream order.
type AtomSpec = (usize, usize, u32, u32, f64);

fn atom_specs(
    l: &LeafLayout,
    pyr: &[Vec<Vec<f32>>],
    plan: &Plan,
    valid: &[bool],
    lb: [u8; 2],
) -> Vec<AtomSpec> {
    let (b0, b1) = (1usize << lb[0], 1usize << lb[1]);
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
    specs
}
