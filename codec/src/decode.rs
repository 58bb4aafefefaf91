//! Leaf decoding and the lifetime cache (thesis §4.7).
//!
//! A leaf texture is the sum of one decoded image per pyramid level. Decoded
//! level images are cached; an image unused for more than
//! `L = a · b^l` frames is dropped, `l` counting pyramid levels up from the
//! leaves (0), so the shared coarse levels live longest (a = 20, b = 4).
//! Block origins are staggered per object at encode time (see
//! `TextureInfo::stagger`), so different objects cross block boundaries on
//! different frames and the misses spread out.
//!
//! What is cached for a node is its level's image of one face, kept
//! *sparse* ([`SparseImage`]: only the blocks the stream coded, as
//! constants or 8×8 blocks — most blocks of a detail level are not coded).
//! A leaf is summed from its levels' blocks, root first, into a reused
//! face-sized buffer that stays in cache, then the MIP reconstruction and
//! the inverse colour/gamma transform write the caller's slice (the
//! engine's mapped staging buffer) directly, on AVX2/F16C where the CPU has
//! them. No full-size image is copied through memory per level, and the
//! resident cache is a fraction of full-size images. Results are
//! bit-identical to summing dense level images in the same order (root,
//! …, leaf, then the MIP prediction), which is what the codec first did.

use std::collections::HashMap;
use std::sync::Arc;

use half::f16;
use half::slice::HalfFloatSliceExt;

use crate::coefs::{Contexts, decode_image, step_of};
use crate::container::{BlockView, Container, TextureInfo};
use crate::dct::Dct8;
use crate::domain::Gamma;
use crate::entropy::Reader;
use crate::error::{CodecError, Result};
use crate::planes::box_down;
use crate::pyramid::Plan;
use crate::sparse::SparseImage;

/// A texel component type the decoder can write: `f32` or `half::f16`.
pub trait OutTexel: Copy + Send {
    /// Converts `src` into `dst` (same length).
    fn convert(src: &[f32], dst: &mut [Self]);
    /// A faster, bit-identical γ = 2 write of the first texels where the
    /// CPU allows (see `write_rgba`); returns how many it wrote.
    #[inline]
    fn write_gamma2(
        _img: &[f32],
        _pred: Option<&[f32]>,
        _n: usize,
        _ch: usize,
        _out: &mut [Self],
    ) -> usize {
        0
    }
}
impl OutTexel for f32 {
    #[inline]
    fn convert(src: &[f32], dst: &mut [Self]) {
        dst.copy_from_slice(src);
    }
}
impl OutTexel for f16 {
    #[inline]
    fn convert(src: &[f32], dst: &mut [Self]) {
        // SIMD (F16C) when the CPU has it.
        dst.convert_from_f32_slice(src);
    }
    #[inline]
    fn write_gamma2(
        img: &[f32],
        pred: Option<&[f32]>,
        n: usize,
        ch: usize,
        out: &mut [Self],
    ) -> usize {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("f16c") {
            // SAFETY: both features were just detected.
            return unsafe { write_gamma2_f16_avx2(img, pred, n, ch, out) };
        }
        let _ = (img, pred, n, ch, out);
        0
    }
}

/// Cache lifetime parameters: `L = a · b^l` frames.
#[derive(Clone, Copy, Debug)]
pub struct Lifetimes {
    pub a: u64,
    pub b: u64,
}

impl Default for Lifetimes {
    fn default() -> Self {
        Self { a: 20, b: 4 }
    }
}

impl Lifetimes {
    /// Lifetime in frames of an image `l` levels above the leaves.
    pub fn frames(&self, l: usize) -> u64 {
        self.a.saturating_mul(self.b.saturating_pow(l as u32))
    }
}

/// Evicted images kept for reuse (their allocations): fresh ones
/// page-fault on first touch. Bounded by what was resident anyway.
const POOL_MAX: usize = 256;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct ImageKey {
    block: usize,
    level: u8,
    node: u16,
    face: u8,
}

struct Entry {
    /// One level's coded blocks, all MIP levels of one face.
    data: SparseImage,
    last_used: u64,
    lifetime: u64,
}

/// A block's verified bytes (compressed, small) and plan, kept with the
/// lifetime of its top level so faces and neighbours don't re-read it.
struct CachedBlock {
    bytes: Vec<u8>,
    plan: Plan,
    last_used: u64,
    lifetime: u64,
}

/// Counters for the engine's statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheStats {
    pub hits: u64,
    pub misses: u64,
    pub evictions: u64,
    pub resident_images: usize,
    pub resident_bytes: usize,
}

/// Decoded-image cache for one container (keys do not name the container:
/// use one cache per container). Not thread-safe by design (one
/// per decode thread); call [`DecodeCache::end_frame`] once per frame.
pub struct DecodeCache {
    life: Lifetimes,
    frame: u64,
    images: HashMap<ImageKey, Entry>,
    blocks: HashMap<usize, CachedBlock>,
    dct: Dct8,
    pool: Vec<SparseImage>,
    /// The leaf being summed: one face, all MIPs, planar (stays in cache).
    sum: Vec<f32>,
    /// One block row of MIP 0, planar.
    strip: Vec<f32>,
    pred: Vec<f32>,
    pred_next: Vec<f32>,
    stats: CacheStats,
}

impl Default for DecodeCache {
    fn default() -> Self {
        Self::new(Lifetimes::default())
    }
}

impl DecodeCache {
    pub fn new(life: Lifetimes) -> Self {
        Self {
            life,
            frame: 0,
            images: HashMap::new(),
            blocks: HashMap::new(),
            dct: Dct8::default(),
            pool: Vec::new(),
            sum: Vec::new(),
            strip: Vec::new(),
            pred: Vec::new(),
            pred_next: Vec::new(),
            stats: CacheStats::default(),
        }
    }

    /// Advances the frame counter and drops images whose lifetime ran out.
    pub fn end_frame(&mut self) {
        self.frame += 1;
        let now = self.frame;
        let before = self.images.len();
        let pool = &mut self.pool;
        self.images.retain(|_, e| {
            let keep = now - e.last_used <= e.lifetime;
            if !keep && pool.len() < POOL_MAX {
                pool.push(std::mem::take(&mut e.data));
            }
            keep
        });
        self.blocks.retain(|_, b| now - b.last_used <= b.lifetime);
        self.stats.evictions += (before - self.images.len()) as u64;
    }

    /// Drops every cached image into the buffer pool (kept for reuse): all
    /// of them, beyond [`POOL_MAX`] — the memory was resident anyway, and
    /// decoding again after a clear then allocates (and faults) nothing.
    pub fn clear(&mut self) {
        let pool = &mut self.pool;
        for (_, mut e) in self.images.drain() {
            pool.push(std::mem::take(&mut e.data));
        }
        self.blocks.clear();
    }

    pub fn stats(&self) -> CacheStats {
        CacheStats {
            resident_images: self.images.len(),
            resident_bytes: self.images.values().map(|e| e.data.bytes()).sum(),
            ..self.stats
        }
    }

    /// Decodes the whole leaf environment/texture map of one parameter
    /// sample — every face and MIP level — into `out`.
    ///
    /// Layout of `out`: RGBA, 4 components per texel (alpha = 1 for RGB
    /// textures), MIP-major, then face (+X, −X, +Y, −Y, +Z, −Z as the
    /// encoder received them), then rows top to bottom, texels left to right;
    /// tightly packed, `layout.texels() * 4` components. Linear radiance.
    pub fn decode_leaf_all<T: OutTexel>(
        &mut self,
        c: &Container,
        object: u32,
        layer: u32,
        sample: [u32; 2],
        out: &mut [T],
    ) -> Result<()> {
        let ti = c.texture_index(object, layer)?;
        let tex = &c.textures()[ti];
        let expected = tex.layout.texels() * 4;
        if out.len() != expected {
            return Err(CodecError::OutputSize {
                got: out.len(),
                expected,
            });
        }
        for face in 0..tex.layout.faces {
            self.decode_face(
                c,
                tex,
                sample,
                face,
                tex.layout.mips - 1,
                |mip| {
                    let o = tex.layout.texel_offset(face, mip) * 4;
                    let n = tex.layout.face_texels(mip) * 4;
                    Some(o..o + n)
                },
                out,
            )?;
        }
        Ok(())
    }

    /// Decodes one face at one MIP level into `out` (`w_mip × h_mip` RGBA
    /// texels, rows top to bottom, tightly packed).
    #[allow(clippy::too_many_arguments)]
    pub fn decode_leaf<T: OutTexel>(
        &mut self,
        c: &Container,
        object: u32,
        layer: u32,
        sample: [u32; 2],
        face: u32,
        mip: u32,
        out: &mut [T],
    ) -> Result<()> {
        let ti = c.texture_index(object, layer)?;
        let tex = &c.textures()[ti];
        let l = &tex.layout;
        if face >= l.faces {
            return Err(CodecError::IndexOutOfRange {
                what: "face",
                got: face as u64,
                limit: l.faces as u64,
            });
        }
        if mip >= l.mips {
            return Err(CodecError::IndexOutOfRange {
                what: "mip",
                got: mip as u64,
                limit: l.mips as u64,
            });
        }
        let expected = l.face_texels(mip) * 4;
        if out.len() != expected {
            return Err(CodecError::OutputSize {
                got: out.len(),
                expected,
            });
        }
        self.decode_face(
            c,
            tex,
            sample,
            face,
            mip,
            |m| (m == mip).then_some(0..expected),
            out,
        )
    }

    /// Finds or decodes the level images of one face's path, sums them,
    /// then writes the MIP levels for which `dest` gives a range of `out`.
    #[allow(clippy::too_many_arguments)]
    fn decode_face<T: OutTexel>(
        &mut self,
        c: &Container,
        tex: &TextureInfo,
        sample: [u32; 2],
        face: u32,
        last_mip: u32,
        dest: impl Fn(u32) -> Option<std::ops::Range<usize>>,
        out: &mut [T],
    ) -> Result<()> {
        let (block, local) = tex.locate(sample)?;
        let frame = self.frame;
        if !self.blocks.contains_key(&block) {
            let bytes = c.block_bytes(block)?.into_owned();
            let plan = BlockView::parse(&bytes, tex, block)?.plan;
            let lifetime = self.life.frames(plan.levels.len());
            self.blocks.insert(
                block,
                CachedBlock {
                    bytes,
                    plan,
                    last_used: frame,
                    lifetime,
                },
            );
        }
        let cb = self.blocks.get_mut(&block).ok_or(CodecError::BadBlock {
            block,
            what: "block vanished from the cache".into(),
        })?;
        cb.last_used = frame;
        let lb = tex.log2b();
        let n_levels = cb.plan.levels.len();
        let path: Vec<ImageKey> = (0..n_levels)
            .map(|level| ImageKey {
                block,
                level: level as u8,
                node: cb.plan.node_of(level, local, lb) as u16,
                face: face as u8,
            })
            .collect();
        let mut missing = Vec::new();
        for (level, k) in path.iter().enumerate() {
            match self.images.get_mut(k) {
                Some(e) => {
                    e.last_used = frame;
                    self.stats.hits += 1;
                }
                None => missing.push(level),
            }
        }
        if !missing.is_empty() {
            self.stats.misses += missing.len() as u64;
            // Take the bytes out while decoding (the decoder borrows self).
            let bytes = self
                .blocks
                .get_mut(&block)
                .map(|b| std::mem::take(&mut b.bytes))
                .unwrap_or_default();
            let result = self.decode_levels(tex, &bytes, block, &path, &missing);
            if let Some(b) = self.blocks.get_mut(&block) {
                b.bytes = bytes;
            }
            result?;
        }
        let vanished = || CodecError::BadBlock {
            block,
            what: "decoded image vanished from the cache".into(),
        };
        let levels = path
            .iter()
            .map(|k| self.images.get(k).map(|e| &e.data))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(vanished)?;
        let l = &tex.layout;
        let ch = l.channels as usize;
        let len: usize = (0..l.mips).map(|m| l.face_texels(m) * ch).sum();
        // (These buffers only grow: shrinking and regrowing would zero them.)
        if self.sum.len() < len {
            self.sum.resize(len, 0.0);
        }
        let gamma = Gamma(c.gamma);
        let mut off = 0;
        for mip in 0..=last_mip {
            let (w, h) = l.mip_size(mip);
            let n = w * h;
            let dst = dest(mip);
            // MIP 0 is needed for the prediction of the others.
            let needed = dst.is_some() || (mip == 0 && last_mip > 0);
            if mip == 0 && needed && (last_mip == 0 || (w % 2 == 0 && h % 2 == 0)) {
                // The largest image by strips of one block row: its sums, its
                // write and the MIP 1 prediction from them stay in L1.
                let o = match dst {
                    Some(r) => Some(out.get_mut(r).ok_or(CodecError::OutputSize {
                        got: 0,
                        expected: n * 4,
                    })?),
                    None => None,
                };
                if last_mip > 0 {
                    let (w1, h1) = l.mip_size(1);
                    if self.pred.len() < w1 * h1 * ch {
                        self.pred.resize(w1 * h1 * ch, 0.0);
                        self.pred_next.resize(w1 * h1 * ch, 0.0);
                    }
                }
                write_mip0_by_strips(
                    &levels,
                    gamma,
                    w,
                    h,
                    ch,
                    &mut self.strip,
                    (last_mip > 0).then_some(&mut self.pred[..]),
                    o,
                );
                off += n * ch;
                continue;
            }
            let img = &mut self.sum[off..off + n * ch];
            if needed {
                // Root first, then each finer level: the order of the sums.
                for (c, plane) in img.chunks_exact_mut(n).enumerate() {
                    plane.fill(0.0);
                    for lv in &levels {
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
            if let Some(r) = dst {
                let o = out.get_mut(r).ok_or(CodecError::OutputSize {
                    got: 0,
                    expected: n * 4,
                })?;
                let pred = (mip > 0).then(|| &self.pred[..n * ch]);
                write_rgba(gamma, &self.sum[off..off + n * ch], pred, n, ch, o);
            }
            off += n * ch;
        }
        Ok(())
    }

    /// Decodes the level images `path[level]` for each of `levels` and
    /// caches them.
    fn decode_levels(
        &mut self,
        tex: &TextureInfo,
        bytes: &[u8],
        block: usize,
        path: &[ImageKey],
        levels: &[usize],
    ) -> Result<()> {
        let view = BlockView::parse(bytes, tex, block)?;
        let n_levels = path.len();
        let frame = self.frame;
        for &level in levels {
            let key = path[level];
            let mut img = self.pool.pop().unwrap_or_default();
            img.clear();
            decode_level(&self.dct, tex, &view, block, key, &mut img)?;
            self.insert(key, img, n_levels - 1 - level, frame);
        }
        Ok(())
    }

    fn insert(&mut self, key: ImageKey, data: SparseImage, up: usize, frame: u64) {
        self.images.insert(
            key,
            Entry {
                data,
                last_used: frame,
                lifetime: self.life.frames(up),
            },
        );
    }
}

/// Whether MIP 0 went by strips, which leaves MIP 1's prediction made.
fn strips_done_mip1(l: &crate::input::LeafLayout, last_mip: u32) -> bool {
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

/// Decodes stream `k` (one level's image of one face, all MIPs) into `img`.
fn decode_level(
    dct: &Dct8,
    tex: &TextureInfo,
    view: &BlockView,
    block: usize,
    k: ImageKey,
    img: &mut SparseImage,
) -> Result<()> {
    let l = &tex.layout;
    let ch = l.channels as usize;
    let si = BlockView::stream_index(
        &view.plan,
        l.faces,
        k.level as usize,
        k.node as usize,
        k.face as u32,
    );
    let corrupt = |what| CodecError::CorruptStream {
        block,
        stream: si,
        what,
    };
    let (steps, bytes) = *view
        .streams
        .get(si)
        .ok_or(corrupt("stream index out of range"))?;
    if steps.iter().any(|&s| s != 0) {
        let mut r = Reader::new(bytes).ok_or(corrupt("stream is not whole words"))?;
        let mut ctx = Contexts::default();
        for mip in 0..l.mips {
            let (w, h) = l.mip_size(mip);
            let idx = *steps.get(mip as usize).ok_or(corrupt("missing step"))?;
            if idx != 0 {
                let mut sink = img.sink(mip as usize, ch);
                decode_image(&mut r, &mut ctx, dct, w, h, ch, step_of(idx), &mut sink)
                    .map_err(corrupt)?;
            }
        }
    }
    img.finish(l.mips as usize * ch);
    Ok(())
}

/// Planar coding-domain image (the leaf's sum of levels, + the MIP
/// prediction above MIP 0) → interleaved linear RGBA, converted to `T`.
fn write_rgba<T: OutTexel>(
    g: Gamma,
    img: &[f32],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [T],
) {
    if g.0 == 2.0 {
        let done = T::write_gamma2(img, pred, n, ch, out);
        write_rgba_with(|v: f32| v * v.abs(), img, pred, n, ch, out, done)
    } else {
        write_rgba_with(|v: f32| g.inverse(v), img, pred, n, ch, out, 0)
    }
}

/// The portable write, from texel `from` on.
#[inline(always)]
fn write_rgba_with<T: OutTexel>(
    inv: impl Fn(f32) -> f32,
    img: &[f32],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [T],
    from: usize,
) {
    const CHUNK: usize = 256;
    if from >= n {
        return;
    }
    let mut tmp = [0.0f32; CHUNK * 4];
    let mut sum = [[0.0f32; CHUNK]; 4];
    for (chunk_i, dst) in out[from * 4..n * 4].chunks_mut(CHUNK * 4).enumerate() {
        let base = from + chunk_i * CHUNK;
        let m = dst.len() / 4;
        // Planes (+ prediction) for this chunk, then the colour transform.
        for (c, s) in sum.iter_mut().enumerate() {
            let s = &mut s[..m];
            if c >= ch {
                s.fill(1.0);
                continue;
            }
            s.copy_from_slice(&img[c * n + base..][..m]);
            if let Some(p) = pred {
                s.iter_mut()
                    .zip(&p[c * n + base..][..m])
                    .for_each(|(a, b)| *a += b);
            }
        }
        // Colour transform in place (planar, vectorisable), then interleave.
        let [y, co, cg, a] = &mut sum;
        for ((y, co), cg) in y[..m].iter_mut().zip(&mut co[..m]).zip(&mut cg[..m]) {
            let t = *y - *cg;
            let (r, g, b) = (inv(t + *co), inv(*y + *cg), inv(t - *co));
            (*y, *co, *cg) = (r, g, b);
        }
        for (px, ((r, g), (b, a))) in tmp[..m * 4]
            .chunks_exact_mut(4)
            .zip(y[..m].iter().zip(&co[..m]).zip(cg[..m].iter().zip(&a[..m])))
        {
            px.copy_from_slice(&[*r, *g, *b, *a]);
        }
        T::convert(&tmp[..m * 4], dst);
    }
}

/// [`write_rgba`] for γ = 2 into f16, eight texels at a time on AVX2/F16C
/// (the same operations in the same order as the portable path, and the
/// same round-to-nearest-even conversion as `half`, so the same bits).
/// Returns how many texels it wrote (a multiple of 8; the rest is left to
/// the portable path).
///
/// # Safety
/// The CPU must support AVX2 and F16C.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,f16c")]
unsafe fn write_gamma2_f16_avx2(
    img: &[f32],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [f16],
) -> usize {
    use std::arch::x86_64::*;
    let n8 = n / 8 * 8;
    let planes = &img[..n * ch];
    let pred = pred.map(|p| &p[..n * ch]);
    let out = &mut out[..n8 * 4];
    // SAFETY: AVX2/F16C are available (the caller's contract); every load
    // reads 8 floats at `c·n + i` with `i + 8 ≤ n8 ≤ n` inside the planes
    // (length-checked above), every store writes 8 halves at `4i + 8j`,
    // `j < 4`, inside `out[..4·n8]`.
    unsafe {
        let sign = _mm256_set1_ps(-0.0);
        let inv = |v: __m256| _mm256_mul_ps(v, _mm256_andnot_ps(sign, v));
        let load = |c: usize, i: usize| {
            let v = _mm256_loadu_ps(planes.as_ptr().add(c * n + i));
            match pred {
                Some(p) => _mm256_add_ps(v, _mm256_loadu_ps(p.as_ptr().add(c * n + i))),
                None => v,
            }
        };
        let o = out.as_mut_ptr() as *mut __m128i;
        for i in (0..n8).step_by(8) {
            let (y, co, cg) = (load(0, i), load(1, i), load(2, i));
            let a = if ch > 3 {
                load(3, i)
            } else {
                _mm256_set1_ps(1.0)
            };
            let t = _mm256_sub_ps(y, cg);
            let r = inv(_mm256_add_ps(t, co));
            let g = inv(_mm256_add_ps(y, cg));
            let b = inv(_mm256_sub_ps(t, co));
            let [r, g, b, a] =
                [r, g, b, a].map(|v| _mm256_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(v));
            let rg_lo = _mm_unpacklo_epi16(r, g);
            let rg_hi = _mm_unpackhi_epi16(r, g);
            let ba_lo = _mm_unpacklo_epi16(b, a);
            let ba_hi = _mm_unpackhi_epi16(b, a);
            let q = o.add(i / 2);
            _mm_storeu_si128(q, _mm_unpacklo_epi32(rg_lo, ba_lo));
            _mm_storeu_si128(q.add(1), _mm_unpackhi_epi32(rg_lo, ba_lo));
            _mm_storeu_si128(q.add(2), _mm_unpacklo_epi32(rg_hi, ba_hi));
            _mm_storeu_si128(q.add(3), _mm_unpackhi_epi32(rg_hi, ba_hi));
        }
    }
    n8
}

/// Convenience: decode one whole leaf without keeping a cache.
pub fn decode_leaf_all<T: OutTexel>(
    c: &Container,
    object: u32,
    layer: u32,
    sample: [u32; 2],
    out: &mut [T],
) -> Result<()> {
    DecodeCache::default().decode_leaf_all(c, object, layer, sample, out)
}

/// Shared handle type for engines that decode on several threads.
pub type SharedContainer = Arc<Container>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_f16_write_matches_the_portable_one() {
        let mut seed = 3u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 40) as f32 / (1u64 << 24) as f32 - 0.3) * 40.0
        };
        // Lengths with and without an 8-texel tail; RGB and RGBA; with and
        // without a MIP prediction; values spanning f16's range and beyond.
        for (n, ch, with_pred) in [(64, 3, false), (67, 4, true), (5, 3, true), (1, 4, false)] {
            let img: Vec<f32> = (0..n * ch).map(|_| next()).collect();
            let pred: Vec<f32> = (0..n * ch).map(|_| next() * 0.1).collect();
            let pred = with_pred.then_some(&pred[..]);
            let mut fast = vec![f16::ZERO; n * 4];
            let mut portable = vec![f16::ZERO; n * 4];
            write_rgba(Gamma(2.0), &img, pred, n, ch, &mut fast);
            write_rgba_with(|v: f32| v * v.abs(), &img, pred, n, ch, &mut portable, 0);
            let bits = |v: &[f16]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&portable), "n {n}, ch {ch}");
        }
    }
}
