//! Quantisation and binarisation of one image's DCT coefficients.
//!
//! Per 8×8 block, in raster order: a "coded" flag (context: how many of the
//! left/upper neighbours were coded); then, CABAC-style, for each zig-zag
//! position a significance flag and, after each nonzero, a "last" flag;
//! magnitudes as adaptive unary up to 15 then Exp-Golomb; signs raw. The DC
//! is predicted from the left (or upper) block's quantised DC, which is
//! what the smooth top pyramid levels need. Contexts are kept apart for
//! luma, chroma and alpha.

use crate::dct::{Dct8, N, NN, ZIGZAG, block_grid, forward_plane};
use crate::domain::CHANNEL_SSE_WEIGHT;
use crate::entropy::{BitSink, Ctx, Reader};

const UNARY: usize = 15;
const EG_MAX_PREFIX: usize = 30;
/// Quantised magnitudes are clamped here so Exp-Golomb stays within its cap.
const MAX_MAG: u32 = 1 << 28;
/// Rounding offsets: plain rounding for DC, a dead zone for AC (RD-better
/// for Laplacian-distributed coefficients at low rates).
const ROUND_DC: f32 = 0.5;
const ROUND_AC: f32 = 1.0 / 3.0;

/// Quantiser step for a stored step index; 0 means "image not coded".
/// Quarter-octave steps spanning 2^-31.75 ..= 2^31.75.
pub fn step_of(idx: u8) -> f32 {
    (2.0f32).powf((idx as f32 - 128.0) / 4.0)
}

/// Smallest index whose step is ≥ `s` (saturating).
pub fn idx_at_least(s: f32) -> u8 {
    let i = (s.max(1e-30).log2() * 4.0 + 128.0).ceil();
    i.clamp(1.0, 255.0) as u8
}

#[derive(Clone)]
struct ClassCtx {
    coded: [Ctx; 3],
    sig: [Ctx; NN],
    last: [Ctx; NN],
    mag: [[Ctx; UNARY]; 2],
    eg: [Ctx; EG_MAX_PREFIX + 1],
}

impl Default for ClassCtx {
    fn default() -> Self {
        Self {
            coded: [Ctx::default(); 3],
            sig: [Ctx::default(); NN],
            last: [Ctx::default(); NN],
            mag: [[Ctx::default(); UNARY]; 2],
            eg: [Ctx::default(); EG_MAX_PREFIX + 1],
        }
    }
}

/// Adaptive state of one stream (shared by the images coded in it).
#[derive(Clone, Default)]
pub struct Contexts {
    class: [ClassCtx; 3],
}

fn class_of(channel: usize) -> usize {
    match channel {
        0 => 0,
        1 | 2 => 1,
        _ => 2,
    }
}

/// One plane's coefficients with per-block summaries for fast RD sweeps.
pub struct CoefPlane {
    coefs: Vec<f32>,
    ac_max: Vec<f32>,
    ac_energy: Vec<f64>,
}

/// One image (all channels of one face at one MIP) in the DCT domain.
pub struct CoefImage {
    pub w: usize,
    pub h: usize,
    planes: Vec<CoefPlane>,
}

impl CoefImage {
    /// `planar` holds `channels` planes of `w × h` back to back.
    pub fn new(dct: &mut Dct8, planar: &[f32], w: usize, h: usize, channels: usize) -> Self {
        let planes = (0..channels)
            .map(|c| {
                let coefs = forward_plane(dct, &planar[c * w * h..][..w * h], w, h);
                let (ac_max, ac_energy) = coefs
                    .chunks_exact(NN)
                    .map(|b| {
                        let ac = &b[1..];
                        (
                            ac.iter().fold(0.0f32, |m, v| m.max(v.abs())),
                            ac.iter().map(|&v| v as f64 * v as f64).sum::<f64>(),
                        )
                    })
                    .unzip();
                CoefPlane {
                    coefs,
                    ac_max,
                    ac_energy,
                }
            })
            .collect();
        Self { w, h, planes }
    }

    pub fn max_abs(&self) -> f32 {
        self.planes
            .iter()
            .flat_map(|p| p.coefs.iter())
            .fold(0.0f32, |m, v| m.max(v.abs()))
    }

    /// Weighted squared error of not coding the image at all.
    pub fn energy(&self) -> f64 {
        self.planes
            .iter()
            .enumerate()
            .map(|(c, p)| {
                CHANNEL_SSE_WEIGHT[c] * p.coefs.iter().map(|&v| v as f64 * v as f64).sum::<f64>()
            })
            .sum()
    }
}

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

#[inline(always)]
fn decode_mag(r: &mut Reader, cc: &mut ClassCtx, band: usize) -> Result<u32, &'static str> {
    for k in 0..UNARY {
        if !r.bit(&mut cc.mag[band][k]) {
            return Ok(k as u32);
        }
    }
    let mut n = 0;
    while r.bit(&mut cc.eg[n.min(EG_MAX_PREFIX)]) {
        n += 1;
        if n > EG_MAX_PREFIX {
            return Err("Exp-Golomb prefix too long");
        }
    }
    let mut v: u32 = 1;
    for _ in 0..n {
        v = (v << 1) | r.bypass() as u32;
    }
    Ok(v - 1 + UNARY as u32)
}

/// Where [`decode_image`] puts each decoded block of plane `c`, whose
/// texels are `x0..x0 + xs` × `y0..y0 + ys` (`xs`, `ys` ≤ 8 at the image's
/// right and bottom edges).
pub trait BlockSink {
    /// A DC-only block: the constant `v`.
    fn constant(&mut self, c: usize, x0: usize, y0: usize, xs: usize, ys: usize, v: f32);
    /// An inverse-transformed block (raster 8×8; its top-left `xs × ys` used).
    fn block(&mut self, c: usize, x0: usize, y0: usize, xs: usize, ys: usize, b: &[f32; NN]);
}

/// Adds every block into `channels` planes of `w × h` (planar).
pub struct AddToPlanes<'a> {
    pub out: &'a mut [f32],
    pub w: usize,
    pub h: usize,
}

impl BlockSink for AddToPlanes<'_> {
    #[inline(always)]
    fn constant(&mut self, c: usize, x0: usize, y0: usize, xs: usize, ys: usize, v: f32) {
        let (w, h) = (self.w, self.h);
        let plane = &mut self.out[c * w * h..][..w * h];
        for row in plane[y0 * w + x0..].chunks_mut(w).take(ys) {
            row[..xs].iter_mut().for_each(|p| *p += v);
        }
    }
    #[inline(always)]
    fn block(&mut self, c: usize, x0: usize, y0: usize, xs: usize, ys: usize, b: &[f32; NN]) {
        let (w, h) = (self.w, self.h);
        let plane = &mut self.out[c * w * h..][..w * h];
        for (row, src) in plane[y0 * w + x0..]
            .chunks_mut(w)
            .take(ys)
            .zip(b.chunks_exact(N))
        {
            row[..xs].iter_mut().zip(src).for_each(|(p, v)| *p += v);
        }
    }
}

/// Decodes one image coded by [`encode_image`] and *adds* it to `out`
/// (`channels` planes of `w × h`, planar). Bad data gives an error, never a
/// panic or an out-of-range write.
#[allow(clippy::too_many_arguments)]
pub fn decode_image_add(
    r: &mut Reader,
    ctx: &mut Contexts,
    dct: &Dct8,
    w: usize,
    h: usize,
    channels: usize,
    step: f32,
    out: &mut [f32],
) -> Result<(), &'static str> {
    if out.len() < channels * w * h {
        return Err("output too small");
    }
    decode_image(
        r,
        ctx,
        dct,
        w,
        h,
        channels,
        step,
        &mut AddToPlanes { out, w, h },
    )
}

/// Decodes one image coded by [`encode_image`] (`channels` planes of
/// `w × h`) block by block into `sink`: the blocks the stream codes, each
/// a constant or an inverse-transformed 8×8 block, in plane, then raster
/// block order. Bad data gives an error, never a panic.
///
/// Runs as AVX2 code where the CPU has it (chosen at run time; the
/// arithmetic is the same operations in the same order, and Rust never
/// fuses multiply-adds, so results are bit-identical either way).
#[allow(clippy::too_many_arguments)]
pub fn decode_image<S: BlockSink>(
    r: &mut Reader,
    ctx: &mut Contexts,
    dct: &Dct8,
    w: usize,
    h: usize,
    channels: usize,
    step: f32,
    sink: &mut S,
) -> Result<(), &'static str> {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { decode_image_avx2(r, ctx, dct, w, h, channels, step, sink) };
    }
    decode_image_impl::<S, false>(r, ctx, dct, w, h, channels, step, sink)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn decode_image_avx2<S: BlockSink>(
    r: &mut Reader,
    ctx: &mut Contexts,
    dct: &Dct8,
    w: usize,
    h: usize,
    channels: usize,
    step: f32,
    sink: &mut S,
) -> Result<(), &'static str> {
    decode_image_impl::<S, true>(r, ctx, dct, w, h, channels, step, sink)
}

/// `AVX2`: only ever instantiated as `true` inside [`decode_image_avx2`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn decode_image_impl<S: BlockSink, const AVX2: bool>(
    r: &mut Reader,
    ctx: &mut Contexts,
    dct: &Dct8,
    w: usize,
    h: usize,
    channels: usize,
    step: f32,
    sink: &mut S,
) -> Result<(), &'static str> {
    // The decoder's state in a local, so it lives in registers rather than
    // being stored through `r` at every decision.
    let mut rd = r.clone();
    let result = decode_image_body::<S, AVX2>(&mut rd, ctx, dct, w, h, channels, step, sink);
    *r = rd;
    result
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn decode_image_body<S: BlockSink, const AVX2: bool>(
    r: &mut Reader,
    ctx: &mut Contexts,
    dct: &Dct8,
    w: usize,
    h: usize,
    channels: usize,
    step: f32,
    sink: &mut S,
) -> Result<(), &'static str> {
    let (bw, bh) = block_grid(w, h);
    let mut coded = vec![false; bw];
    let mut dc_above = vec![0i32; bw];
    // Dequantised coefficients in raster order; all zero between blocks.
    let mut blk = [0.0f32; NN];
    for c in 0..channels {
        let cc = &mut ctx.class[class_of(c)];
        coded.iter_mut().for_each(|v| *v = false);
        dc_above.iter_mut().for_each(|v| *v = 0);
        for by in 0..bh {
            let mut left_coded = false;
            let mut dc_left = 0;
            let y0 = by * N;
            let ys = N.min(h - y0);
            for bx in 0..bw {
                let pred = if bx == 0 { dc_above[0] } else { dc_left };
                let nctx = left_coded as usize + coded[bx] as usize;
                let is_coded = r.bit(&mut cc.coded[nctx]);
                let (q0, any_ac) = if is_coded {
                    decode_block(r, cc, step, &mut blk)?
                } else {
                    (0, false)
                };
                let dc = q0.checked_add(pred).ok_or("DC overflow")?;
                left_coded = is_coded;
                coded[bx] = is_coded;
                dc_left = dc;
                dc_above[bx] = dc;
                let x0 = bx * N;
                let xs = N.min(w - x0);
                if !any_ac {
                    if dc != 0 {
                        // DC-only block: a constant (orthonormal DC gain is 1/8).
                        sink.constant(c, x0, y0, xs, ys, dc as f32 * step * 0.125);
                    }
                    continue;
                }
                if dc != 0 {
                    blk[0] = dc as f32 * step;
                }
                #[cfg(target_arch = "x86_64")]
                if AVX2 {
                    // SAFETY: AVX2 code is only instantiated behind the
                    // run-time check in `decode_image`.
                    unsafe { crate::dct::inverse_avx2(dct, &mut blk) };
                } else {
                    dct.inverse(&mut blk);
                }
                #[cfg(not(target_arch = "x86_64"))]
                dct.inverse(&mut blk);
                sink.block(c, x0, y0, xs, ys, &blk);
                blk = [0.0; NN];
            }
        }
    }
    if r.failed() {
        return Err("range decoder rejected the data");
    }
    Ok(())
}

/// Decodes one coded block: writes its dequantised AC coefficients into
/// `blk` (raster order, which must be all zero) and returns the quantised
/// DC residual and whether any AC coefficient is nonzero.
#[inline(always)]
fn decode_block(
    r: &mut Reader,
    cc: &mut ClassCtx,
    step: f32,
    blk: &mut [f32; NN],
) -> Result<(i32, bool), &'static str> {
    let mut q0 = 0;
    let mut any_ac = false;
    for (i, &zz) in ZIGZAG.iter().enumerate() {
        let sig = if i < NN - 1 {
            r.bit(&mut cc.sig[i])
        } else {
            true
        };
        if !sig {
            continue;
        }
        let m = decode_mag(r, cc, i.min(1))? + 1;
        let m = i32::try_from(m).map_err(|_| "magnitude overflow")?;
        let v = if r.bypass() { -m } else { m };
        if i == 0 {
            q0 = v;
        } else {
            blk[zz] = v as f32 * step;
            any_ac = true;
        }
        if i == NN - 1 || r.bit(&mut cc.last[i]) {
            break;
        }
        if r.failed() {
            return Err("range decoder rejected the data");
        }
    }
    Ok((q0, any_ac))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entropy::{CostMeter, Writer};

    #[test]
    fn image_round_trip_at_fine_step() {
        let (w, h, ch) = (19, 13, 4);
        let planar: Vec<f32> = (0..w * h * ch)
            .map(|i| {
                ((i % w) as f32 * 0.3).sin() * 4.0
                    + (i / (w * h)) as f32
                    + ((i * 7919) % 13) as f32 * 0.01
            })
            .collect();
        let mut dct = Dct8::default();
        let img = CoefImage::new(&mut dct, &planar, w, h, ch);
        let step = step_of(100);
        let mut wtr = Writer::default();
        let sse = encode_image(&mut wtr, &mut Contexts::default(), &img, step);
        let mut meter = CostMeter::default();
        let sse2 = encode_image(&mut meter, &mut Contexts::default(), &img, step);
        assert_eq!(sse, sse2);
        let bytes = wtr.finish().unwrap();
        assert!((bytes.len() as f64 * 8.0 - meter.bits).abs() < 0.05 * meter.bits + 96.0);
        let mut out = vec![0.0; w * h * ch];
        let mut r = Reader::new(&bytes).unwrap();
        decode_image_add(
            &mut r,
            &mut Contexts::default(),
            &dct,
            w,
            h,
            ch,
            step,
            &mut out,
        )
        .unwrap();
        let mut real_sse = 0.0;
        for c in 0..ch {
            for i in 0..w * h {
                let e = (out[c * w * h + i] - planar[c * w * h + i]) as f64;
                real_sse += CHANNEL_SSE_WEIGHT[c] * e * e;
            }
        }
        // Padding makes the DCT-domain SSE cover more texels than the crop.
        assert!(real_sse <= sse * 1.01 + 1e-9, "{real_sse} > {sse}");
        let max_err = out
            .iter()
            .zip(&planar)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        assert!(max_err < 64.0 * step, "max error {max_err}");
    }

    #[test]
    fn step_index_is_monotone() {
        assert_eq!(step_of(128), 1.0);
        assert!(step_of(idx_at_least(0.3)) >= 0.3);
        assert!(step_of(idx_at_least(0.3) - 1) < 0.3);
    }
}
