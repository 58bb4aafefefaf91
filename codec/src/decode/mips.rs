//! Summing a leaf's level images per MIP level and writing them: MIP 0
//! by strips of one block row where it can, the others whole, each MIP
//! above 0 plus the decimated finest level.

use super::LeafSink;
use super::texel::{OutTexel, write_rgba};
use crate::domain::Gamma;
use crate::error::{CodecError, Result};
use crate::input::LeafLayout;
use crate::planes::box_down;
use crate::sparse::SparseImage;

/// Whether MIP 0 went by strips, which leaves MIP 1's prediction made.
fn strips_done_mip1(l: &LeafLayout, last_mip: u32) -> bool {
    let (w, h) = l.mip_size(0);
    last_mip > 0 && w % 2 == 0 && h % 2 == 0
}

/// MIP 0 of one face, one block row (8 texel rows) at a time: the sum of
/// the levels' blocks (root first), written to `out` if given, and, with
/// `pred1`, box-decimated into the MIP 1 prediction (`w`, `h` even then).
/// The same operations per texel as summing and decimating whole images.
#[allow(clippy::too_many_arguments)]
fn write_mip0_by_strips<T: OutTexel>(
    levels: &[&SparseImage],
    gamma: Gamma,
    w: usize,
    h: usize,
    ch: usize,
    strip: &mut Vec<f32>,
    mut pred1: Option<&mut [f32]>,
    mut out: Option<&mut [T]>,
) {
    const N: usize = crate::dct::N;
    if strip.len() < ch * N * w {
        strip.resize(ch * N * w, 0.0);
    }
    // Per level and channel: the blocks of MIP 0's plane not yet added.
    let mut todo: Vec<std::ops::Range<u32>> = levels
        .iter()
        .flat_map(|lv| (0..ch).map(|c| lv.plane_range(c)))
        .collect();
    let (w1, h1) = (w / 2, h / 2);
    for y0 in (0..h).step_by(N) {
        let ys = N.min(h - y0);
        let ns = ys * w;
        let strip = &mut strip[..ch * ns];
        for (c, plane) in strip.chunks_exact_mut(ns).enumerate() {
            plane.fill(0.0);
            for (li, lv) in levels.iter().enumerate() {
                lv.add_row(&mut todo[li * ch + c], y0, plane, w);
            }
            if let Some(p) = pred1.as_deref_mut() {
                let p = &mut p[c * w1 * h1 + (y0 / 2) * w1..][..(ys / 2) * w1];
                box_down(plane, w, ys, 1, p);
            }
        }
        if let Some(o) = out.as_deref_mut() {
            write_rgba(gamma, strip, None, ns, ch, &mut o[y0 * w * 4..][..ns * 4]);
        }
    }
}

/// The decoder's reused buffers. (They only grow: shrinking and regrowing
/// would zero them.)
#[derive(Default)]
pub(super) struct Scratch {
    /// The leaf being summed: one face, all MIPs, planar (stays in cache).
    sum: Vec<f32>,
    /// One block row of MIP 0, planar.
    strip: Vec<f32>,
    pred: Vec<f32>,
    pred_next: Vec<f32>,
}

impl Scratch {
    /// Sums `levels` (root first) for MIP levels `0..=last_mip` and writes
    /// those of `face` that `sink` asks for.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn write_mips<T: OutTexel>(
        &mut self,
        gamma: Gamma,
        l: &LeafLayout,
        levels: &[&SparseImage],
        last_mip: u32,
        face: u32,
        sink: &mut impl LeafSink<T>,
    ) -> Result<()> {
        let ch = l.channels as usize;
        let len: usize = (0..l.mips).map(|m| l.face_texels(m) * ch).sum();
        if self.sum.len() < len {
            self.sum.resize(len, 0.0);
        }
        let mut off = 0;
        for mip in 0..=last_mip {
            let (w, h) = l.mip_size(mip);
            let n = w * h;
            let dst = sink.level(face, mip, n);
            if let Some(d) = &dst
                && d.len() != n * 4
            {
                return Err(CodecError::OutputSize {
                    got: d.len(),
                    expected: n * 4,
                });
            }
            // MIP 0 is needed for the prediction of the others.
            let needed = dst.is_some() || (mip == 0 && last_mip > 0);
            if mip == 0 && needed && (last_mip == 0 || (w % 2 == 0 && h % 2 == 0)) {
                self.mip0_by_strips(gamma, l, levels, last_mip, dst);
            } else {
                self.sum_mip(l, levels, mip, last_mip, needed, off);
                if let Some(o) = dst {
                    let pred = (mip > 0).then(|| &self.pred[..n * ch]);
                    write_rgba(gamma, &self.sum[off..off + n * ch], pred, n, ch, o);
                }
            }
            off += n * ch;
        }
        Ok(())
    }

    /// The largest image by strips of one block row: its sums, its write
    /// and the MIP 1 prediction from them stay in L1.
    fn mip0_by_strips<T: OutTexel>(
        &mut self,
        gamma: Gamma,
        l: &LeafLayout,
        levels: &[&SparseImage],
        last_mip: u32,
        out: Option<&mut [T]>,
    ) {
        let (w, h) = l.mip_size(0);
        let ch = l.channels as usize;
        if last_mip > 0 {
            let (w1, h1) = l.mip_size(1);
            if self.pred.len() < w1 * h1 * ch {
                self.pred.resize(w1 * h1 * ch, 0.0);
                self.pred_next.resize(w1 * h1 * ch, 0.0);
            }
        }
        write_mip0_by_strips(
            levels,
            gamma,
            w,
            h,
            ch,
            &mut self.strip,
            (last_mip > 0).then_some(&mut self.pred[..]),
            out,
        );
    }

    /// Sums MIP `mip` (at `off` in `sum`) if `needed`, and brings the MIP
    /// prediction down to it.
    fn sum_mip(
        &mut self,
        l: &LeafLayout,
        levels: &[&SparseImage],
        mip: u32,
        last_mip: u32,
        needed: bool,
        off: usize,
    ) {
        let ch = l.channels as usize;
        let (w, h) = l.mip_size(mip);
        let n = w * h;
        let img = &mut self.sum[off..off + n * ch];
        if needed {
            // Root first, then each finer level: the order of the sums.
            for (c, plane) in img.chunks_exact_mut(n).enumerate() {
                plane.fill(0.0);
                for lv in levels {
                    lv.add_plane(mip as usize * ch + c, plane, w);
                }
            }
        }
        // MIP m adds the decimated finest level (the leaf's own MIP 0).
        if mip == 1 && !strips_done_mip1(l, last_mip) {
            let (pw, ph) = l.mip_size(0);
            if self.pred.len() < n * ch {
                self.pred.resize(n * ch, 0.0);
                self.pred_next.resize(n * ch, 0.0);
            }
            box_down(&self.sum[..pw * ph * ch], pw, ph, ch, &mut self.pred);
        } else if mip > 1 {
            let (pw, ph) = l.mip_size(mip - 1);
            box_down(&self.pred, pw, ph, ch, &mut self.pred_next);
            std::mem::swap(&mut self.pred, &mut self.pred_next);
        }
    }
}
