//! A decoded pyramid-level image kept sparse: the blocks its stream coded,
//! nothing else.
//!
//! At 300–800:1 most blocks of a detail level are not coded at all (on the
//! teapot PEM's leaf level 6 % carry AC terms and 9 % only a DC), so the
//! decode cache keeps each level's image of one face (all MIPs, planar
//! channels) as a list of constant and 8×8 blocks. A leaf is then summed
//! from its levels into a small, reused buffer, instead of copying
//! full-size prefix images through memory.

use crate::coefs::BlockSink;
use crate::dct::{N, NN};

/// One coded block: texels `x0..x0 + xs` × `y0..y0 + ys` of its plane get
/// `dc`, or the 8×8 values at `values[at..at + 64]`.
#[derive(Clone, Copy, Debug)]
struct Rec {
    x0: u32,
    y0: u32,
    xs: u8,
    ys: u8,
    at: u32,
    dc: f32,
}

impl Rec {
    #[inline(always)]
    fn new(x0: usize, y0: usize, xs: usize, ys: usize, at: u32, dc: f32) -> Self {
        Self {
            x0: x0 as u32,
            y0: y0 as u32,
            xs: xs as u8,
            ys: ys as u8,
            at,
            dc,
        }
    }
}

const CONSTANT: u32 = u32::MAX;

/// The coded blocks of one face's images, per (MIP, channel) plane.
#[derive(Clone, Debug, Default)]
pub struct SparseImage {
    /// Where plane `k = mip · channels + c` starts in `recs`; its blocks are
    /// `recs[starts[k]..starts[k + 1]]` (one more entry than planes).
    starts: Vec<u32>,
    recs: Vec<Rec>,
    values: Vec<f32>,
}

impl SparseImage {
    /// Empties it, keeping the allocations.
    pub fn clear(&mut self) {
        self.starts.clear();
        self.recs.clear();
        self.values.clear();
    }

    /// A sink for the blocks of plane set `mip` (planes `mip · channels +
    /// c`); planes must be filled in increasing order.
    pub fn sink(&mut self, mip: usize, channels: usize) -> SparseSink<'_> {
        SparseSink {
            img: self,
            base: mip * channels,
        }
    }

    /// Closes the plane list after the last plane set was filled (or none):
    /// `planes` = MIPs × channels.
    pub fn finish(&mut self, planes: usize) {
        self.open_until(planes);
    }

    fn open_until(&mut self, k: usize) {
        while self.starts.len() <= k {
            self.starts.push(self.recs.len() as u32);
        }
    }

    /// Heap bytes held (for the cache statistics).
    pub fn bytes(&self) -> usize {
        self.starts.capacity() * 4
            + self.recs.capacity() * std::mem::size_of::<Rec>()
            + self.values.capacity() * 4
    }

    /// The blocks of plane `k` (empty past the planes filled), for
    /// [`SparseImage::add_row`].
    pub fn plane_range(&self, k: usize) -> std::ops::Range<u32> {
        match (self.starts.get(k), self.starts.get(k + 1)) {
            (Some(&a), Some(&b)) => a..b,
            _ => 0..0,
        }
    }

    /// Adds the blocks at the front of `todo` (from [`SparseImage::plane_range`])
    /// that lie in the block row starting at texel row `y0` into `strip`,
    /// that row's texels (`w` wide), and drops them from `todo`. Rows must
    /// be visited top to bottom.
    #[inline]
    pub fn add_row(&self, todo: &mut std::ops::Range<u32>, y0: usize, strip: &mut [f32], w: usize) {
        let from = todo.start as usize;
        let mut to = from;
        let recs = &self.recs[..(todo.end as usize).min(self.recs.len())];
        while to < recs.len() && recs[to].y0 as usize <= y0 {
            to += 1;
        }
        todo.start = to as u32;
        let recs = &recs[from..to];
        if recs.is_empty() {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            return unsafe { add_avx2(recs, &self.values, strip, w, y0) };
        }
        add(recs, &self.values, strip, w, y0)
    }

    /// Adds plane `k`'s blocks into `plane` (`w` texels wide). Planes past
    /// the ones filled add nothing. AVX2 code where the CPU has it (the
    /// same additions, so the same results).
    #[inline]
    pub fn add_plane(&self, k: usize, plane: &mut [f32], w: usize) {
        let (Some(&a), Some(&b)) = (self.starts.get(k), self.starts.get(k + 1)) else {
            return;
        };
        let recs = &self.recs[a as usize..b as usize];
        if recs.is_empty() {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            return unsafe { add_avx2(recs, &self.values, plane, w, 0) };
        }
        add(recs, &self.values, plane, w, 0)
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn add_avx2(recs: &[Rec], values: &[f32], plane: &mut [f32], w: usize, y_origin: usize) {
    add(recs, values, plane, w, y_origin)
}

/// Adds `recs` into `plane`, whose first row is texel row `y_origin`
/// (blocks above it, which the decoder never leaves, are skipped).
#[inline(always)]
fn add(recs: &[Rec], values: &[f32], plane: &mut [f32], w: usize, y_origin: usize) {
    for r in recs {
        let (x0, xs, ys) = (r.x0 as usize, r.xs as usize, r.ys as usize);
        let Some(y0) = (r.y0 as usize).checked_sub(y_origin) else {
            continue;
        };
        let base = y0 * w + x0;
        if xs == N && ys == N {
            // Whole blocks (almost all of them): fixed-size rows.
            let rows = &mut plane[base..base + (N - 1) * w + N];
            if r.at == CONSTANT {
                for y in 0..N {
                    let row: &mut [f32; N] = (&mut rows[y * w..y * w + N]).try_into().unwrap();
                    for p in row {
                        *p += r.dc;
                    }
                }
            } else {
                let v: &[f32; NN] = values[r.at as usize..][..NN].try_into().unwrap();
                for y in 0..N {
                    let row: &mut [f32; N] = (&mut rows[y * w..y * w + N]).try_into().unwrap();
                    for (p, v) in row.iter_mut().zip(&v[y * N..y * N + N]) {
                        *p += v;
                    }
                }
            }
            continue;
        }
        let rows = plane[base..].chunks_mut(w).take(ys);
        if r.at == CONSTANT {
            for row in rows {
                row[..xs].iter_mut().for_each(|p| *p += r.dc);
            }
        } else {
            let v = &values[r.at as usize..][..NN];
            for (row, src) in rows.zip(v.chunks_exact(N)) {
                row[..xs].iter_mut().zip(src).for_each(|(p, v)| *p += v);
            }
        }
    }
}

/// Appends decoded blocks to a [`SparseImage`].
pub struct SparseSink<'a> {
    img: &'a mut SparseImage,
    base: usize,
}

impl SparseSink<'_> {
    #[inline(always)]
    fn push(&mut self, c: usize, rec: Rec) {
        self.img.open_until(self.base + c);
        self.img.recs.push(rec);
    }
}

impl BlockSink for SparseSink<'_> {
    #[inline(always)]
    fn constant(&mut self, c: usize, x0: usize, y0: usize, xs: usize, ys: usize, v: f32) {
        self.push(c, Rec::new(x0, y0, xs, ys, CONSTANT, v));
    }
    #[inline(always)]
    fn block(&mut self, c: usize, x0: usize, y0: usize, xs: usize, ys: usize, b: &[f32; NN]) {
        let at = self.img.values.len() as u32;
        self.img.values.extend_from_slice(b);
        self.push(c, Rec::new(x0, y0, xs, ys, at, 0.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coefs::AddToPlanes;

    #[test]
    fn sparse_adds_like_dense() {
        // Two plane sets (MIPs) of 2 channels, 11×9 then 5×4; plane 1 of
        // the first set and all of the second left empty but one block.
        let (ch, sizes) = (2usize, [(11usize, 9usize), (5, 4)]);
        let mut img = SparseImage::default();
        let mut dense: Vec<Vec<f32>> = sizes.iter().map(|&(w, h)| vec![0.5; w * h * ch]).collect();
        let mut b = [0.0f32; NN];
        for (i, v) in b.iter_mut().enumerate() {
            *v = i as f32 * 0.25 - 3.0;
        }
        let calls: [(usize, usize, usize, usize, usize, Option<f32>); 4] = [
            (0, 0, 0, 8, 8, None),
            (0, 8, 8, 3, 1, Some(2.0)),
            (0, 8, 0, 3, 8, None),
            (1, 0, 0, 5, 4, Some(-1.5)),
        ];
        for (mip, &(w, h)) in sizes.iter().enumerate() {
            let mut sink = img.sink(mip, ch);
            let mut add = AddToPlanes {
                out: &mut dense[mip],
                w,
                h,
            };
            for &(c, x0, y0, xs, ys, dc) in &calls[if mip == 0 { 0..3 } else { 3..4 }] {
                match dc {
                    Some(v) => {
                        sink.constant(c, x0, y0, xs, ys, v);
                        add.constant(c, x0, y0, xs, ys, v);
                    }
                    None => {
                        sink.block(c, x0, y0, xs, ys, &b);
                        add.block(c, x0, y0, xs, ys, &b);
                    }
                }
            }
        }
        img.finish(sizes.len() * ch);
        for (mip, &(w, h)) in sizes.iter().enumerate() {
            for c in 0..ch {
                let mut plane = vec![0.5; w * h];
                img.add_plane(mip * ch + c, &mut plane, w);
                assert_eq!(
                    plane,
                    dense[mip][c * w * h..][..w * h],
                    "mip {mip} plane {c}"
                );
            }
        }
        // Nothing for planes past the end.
        let mut plane = vec![0.5; 4];
        img.add_plane(99, &mut plane, 2);
        assert_eq!(plane, vec![0.5; 4]);
    }
}
