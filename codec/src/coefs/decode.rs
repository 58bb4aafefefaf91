//! Decoding one image's coefficients into blocks for a [`BlockSink`],
//! on AVX2 where the CPU has it.

use super::{ClassCtx, Contexts, EG_MAX_PREFIX, UNARY, class_of};
use crate::dct::{Dct8, N, NN, ZIGZAG, block_grid};
use crate::entropy::Reader;

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

/// Decodes one image coded by [`encode_image`](super::encode_image) and *adds* it to `out`
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

/// Decodes one image coded by [`encode_image`](super::encode_image) (`channels` planes of
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
