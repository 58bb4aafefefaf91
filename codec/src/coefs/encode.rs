//! Coding one image's quantised coefficients (see [`super`] for the
//! binarisation).

use super::{
    ClassCtx, CoefImage, Contexts, EG_MAX_PREFIX, MAX_MAG, ROUND_AC, ROUND_DC, UNARY, class_of,
};
use crate::dct::{NN, block_grid};
use crate::domain::CHANNEL_SSE_WEIGHT;
use crate::entropy::BitSink;

#[inline]
fn quant(c: f32, inv_step: f32, round: f32) -> i32 {
    let m = (c.abs() * inv_step + round).floor().min(MAX_MAG as f32) as i32;
    if c < 0.0 { -m } else { m }
}

/// Codes `img` at quantiser `step` into `sink`; returns the weighted squared
/// error (RGB-equivalent, see [`CHANNEL_SSE_WEIGHT`]).
pub fn encode_image<S: BitSink>(
    sink: &mut S,
    ctx: &mut Contexts,
    img: &CoefImage,
    step: f32,
) -> f64 {
    let inv = 1.0 / step;
    let (bw, bh) = block_grid(img.w, img.h);
    let ac_zero_below = (1.0 - ROUND_AC) * step;
    let mut sse_total = 0.0;
    let mut coded = vec![false; bw];
    for (c, plane) in img.planes.iter().enumerate() {
        let cc = &mut ctx.class[class_of(c)];
        let mut sse = 0.0f64;
        let mut dc_above = vec![0i32; bw];
        coded.iter_mut().for_each(|v| *v = false);
        for by in 0..bh {
            let mut left_coded = false;
            let mut dc_left = dc_above[0];
            for bx in 0..bw {
                let bi = by * bw + bx;
                let b = &plane.coefs[bi * NN..][..NN];
                let mut q = [0i32; NN];
                q[0] = quant(b[0], inv, ROUND_DC);
                let e = b[0] - q[0] as f32 * step;
                sse += (e * e) as f64;
                let mut last = None;
                if plane.ac_max[bi] < ac_zero_below {
                    sse += plane.ac_energy[bi];
                } else {
                    for i in 1..NN {
                        q[i] = quant(b[i], inv, ROUND_AC);
                        let e = b[i] - q[i] as f32 * step;
                        sse += (e * e) as f64;
                        if q[i] != 0 {
                            last = Some(i);
                        }
                    }
                }
                let pred = if bx == 0 { dc_above[0] } else { dc_left };
                let dc = q[0];
                q[0] -= pred;
                if q[0] != 0 && last.is_none() {
                    last = Some(0);
                }
                let nctx = left_coded as usize + coded[bx] as usize;
                sink.bit(&mut cc.coded[nctx], last.is_some());
                if let Some(last) = last {
                    encode_block(sink, cc, &q, last);
                }
                left_coded = last.is_some();
                coded[bx] = left_coded;
                dc_left = dc;
                dc_above[bx] = dc;
            }
        }
        sse_total += CHANNEL_SSE_WEIGHT[c] * sse;
    }
    sse_total
}

fn encode_block<S: BitSink>(sink: &mut S, cc: &mut ClassCtx, q: &[i32; NN], last: usize) {
    for (i, &v) in q.iter().enumerate().take(last + 1) {
        if i < NN - 1 {
            sink.bit(&mut cc.sig[i], v != 0);
        }
        if v == 0 {
            continue;
        }
        encode_mag(sink, cc, i.min(1), v.unsigned_abs() - 1);
        sink.bypass(v < 0);
        if i < NN - 1 {
            sink.bit(&mut cc.last[i], i == last);
        }
    }
}

fn encode_mag<S: BitSink>(sink: &mut S, cc: &mut ClassCtx, band: usize, m: u32) {
    for k in 0..UNARY {
        let more = m as usize > k;
        sink.bit(&mut cc.mag[band][k], more);
        if !more {
            return;
        }
    }
    // Exp-Golomb (k = 0) of the remainder.
    let r = m - UNARY as u32 + 1;
    let n = 31 - r.leading_zeros() as usize;
    for k in 0..n {
        sink.bit(&mut cc.eg[k.min(EG_MAX_PREFIX)], true);
    }
    sink.bit(&mut cc.eg[n.min(EG_MAX_PREFIX)], false);
    for k in (0..n).rev() {
        sink.bypass((r >> k) & 1 == 1);
    }
}
