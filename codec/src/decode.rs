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
//! What is cached for a node is the *prefix sum* of the levels from the
//! root down to that node (its decoded leaf-so-far), not the node's detail
//! alone: a leaf then costs one image addition (its own level) instead of
//! one per level, with the same per-level lifetimes. The MIP reconstruction
//! and the inverse colour/gamma transform are fused into one pass that
//! writes the caller's slice (the engine's mapped staging buffer) directly.

use std::collections::HashMap;
use std::sync::Arc;

use half::f16;
use half::slice::HalfFloatSliceExt;

use crate::coefs::{Contexts, decode_image_add, step_of};
use crate::container::{BlockView, Container, TextureInfo};
use crate::dct::Dct8;
use crate::domain::Gamma;
use crate::entropy::Reader;
use crate::error::{CodecError, Result};
use crate::planes::box_down;
use crate::pyramid::Plan;

/// A texel component type the decoder can write: `f32` or `half::f16`.
pub trait OutTexel: Copy + Send {
    /// Converts `src` into `dst` (same length).
    fn convert(src: &[f32], dst: &mut [Self]);
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

/// Evicted image buffers kept for reuse: fresh ones page-fault on first
/// touch, which costs more than decoding (notably in VMs). Bounded by what
/// was resident anyway.
const POOL_MAX: usize = 256;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct ImageKey {
    block: usize,
    level: u8,
    node: u16,
    face: u8,
}

struct Entry {
    /// All MIP levels of one face, planar channels.
    data: Vec<f32>,
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
    pool: Vec<Vec<f32>>,
    pred: Vec<f32>,
    pred_next: Vec<f32>,
    sum0: Vec<f32>,
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
            pred: Vec::new(),
            pred_next: Vec::new(),
            sum0: Vec::new(),
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

    /// Drops every cached image into the buffer pool (kept for reuse).
    pub fn clear(&mut self) {
        let pool = &mut self.pool;
        for (_, mut e) in self.images.drain() {
            if pool.len() < POOL_MAX {
                pool.push(std::mem::take(&mut e.data));
            }
        }
        self.blocks.clear();
    }

    pub fn stats(&self) -> CacheStats {
        CacheStats {
            resident_images: self.images.len(),
            resident_bytes: self.images.values().map(|e| e.data.len() * 4).sum(),
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

    /// Finds or decodes the leaf prefix sum for one face, then writes the
    /// MIP levels for which `dest` gives a range of `out`.
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
        let plan = cb.plan.clone();
        let lb = tex.log2b();
        let n_levels = plan.levels.len();
        let path: Vec<ImageKey> = (0..n_levels)
            .map(|level| ImageKey {
                block,
                level: level as u8,
                node: plan.node_of(level, local, lb) as u16,
                face: face as u8,
            })
            .collect();
        let leaf_key = path[n_levels - 1];
        // Deepest cached prefix above the leaf; touching it touches its ancestors.
        let deepest = (0..n_levels - 1)
            .rev()
            .find(|&l| self.images.contains_key(&path[l]));
        for k in path
            .iter()
            .take(deepest.map_or(0, |d| d + 1))
            .chain([&leaf_key])
        {
            if let Some(e) = self.images.get_mut(k) {
                e.last_used = frame;
            }
        }
        let start = deepest.map_or(0, |d| d + 1);
        let leaf_cached = self.images.contains_key(&leaf_key);
        self.stats.hits += deepest.map_or(0, |d| d as u64 + 1) + leaf_cached as u64;
        self.stats.misses += (n_levels - 1 - start) as u64 + !leaf_cached as u64;
        if start < n_levels - 1 || !leaf_cached {
            // Take the bytes out while decoding (the decoder borrows self).
            let bytes = self
                .blocks
                .get_mut(&block)
                .map(|b| std::mem::take(&mut b.bytes))
                .unwrap_or_default();
            let result = self.decode_path(tex, &bytes, block, &path, deepest, leaf_cached);
            if let Some(b) = self.blocks.get_mut(&block) {
                b.bytes = bytes;
            }
            result?;
        }
        let missing = || CodecError::BadBlock {
            block,
            what: "decoded image vanished from the cache".into(),
        };
        let parent = &self
            .images
            .get(&path[n_levels - 2])
            .ok_or_else(missing)?
            .data;
        let detail = &self.images.get(&leaf_key).ok_or_else(missing)?.data;
        // Leaf = parent prefix + leaf detail; MIP m also adds the decimated
        // finest level (box is linear: box(p + d) = box(p) + box(d)).
        let l = &tex.layout;
        let ch = l.channels as usize;
        let gamma = Gamma(c.gamma);
        let mut off = 0;
        for mip in 0..=last_mip {
            let (w, h) = l.mip_size(mip);
            let n = w * h;
            let range = off..off + n * ch;
            let (Some(p), Some(d)) = (parent.get(range.clone()), detail.get(range)) else {
                return Err(missing());
            };
            if mip == 1 {
                let (pw, ph) = l.mip_size(0);
                self.pred.resize(n * ch, 0.0);
                box_down(&self.sum0, pw, ph, ch, &mut self.pred);
            } else if mip > 1 {
                let (pw, ph) = l.mip_size(mip - 1);
                self.pred_next.resize(n * ch, 0.0);
                box_down(&self.pred, pw, ph, ch, &mut self.pred_next);
                std::mem::swap(&mut self.pred, &mut self.pred_next);
            }
            if let Some(r) = dest(mip) {
                let o = out.get_mut(r).ok_or(CodecError::OutputSize {
                    got: 0,
                    expected: n * 4,
                })?;
                let pred = if mip > 0 {
                    Some(&self.pred[..n * ch])
                } else {
                    None
                };
                let keep = (mip == 0 && last_mip > 0).then_some(&mut self.sum0);
                write_rgba(gamma, [p, d], pred, n, ch, o, keep);
            } else if mip == 0 && last_mip > 0 {
                self.sum0.clear();
                self.sum0.extend(p.iter().zip(d).map(|(a, b)| a + b));
            }
            off += n * ch;
        }
        Ok(())
    }

    /// Decodes the prefix sums below level `deepest` (cached) down to the
    /// leaf's parent, caching each, and the leaf's own detail image unless
    /// `leaf_cached`.
    fn decode_path(
        &mut self,
        tex: &TextureInfo,
        bytes: &[u8],
        block: usize,
        path: &[ImageKey],
        deepest: Option<usize>,
        leaf_cached: bool,
    ) -> Result<()> {
        let view = BlockView::parse(bytes, tex, block)?;
        let n_levels = path.len();
        let frame = self.frame;
        let l = &tex.layout;
        let len: usize = (0..l.mips)
            .map(|m| l.face_texels(m) * l.channels as usize)
            .sum();
        let start = deepest.map_or(0, |d| d + 1);
        if start < n_levels - 1 {
            let mut cur = self.take_buffer(len);
            match deepest.and_then(|d| self.images.get(&path[d])) {
                Some(e) => cur.copy_from_slice(&e.data),
                None => cur.fill(0.0),
            }
            for (level, key) in path.iter().enumerate().take(n_levels - 1).skip(start) {
                self.decode_stream_add(tex, &view, block, *key, &mut cur)?;
                let data = if level + 2 < n_levels {
                    // A pooled buffer, not a fresh allocation (first touch faults).
                    let mut copy = self.take_buffer(len);
                    copy.copy_from_slice(&cur);
                    copy
                } else {
                    std::mem::take(&mut cur)
                };
                self.insert(*key, data, n_levels - 1 - level, frame);
            }
        }
        if !leaf_cached {
            let mut detail = self.take_buffer(len);
            detail.fill(0.0);
            self.decode_stream_add(tex, &view, block, path[n_levels - 1], &mut detail)?;
            self.insert(path[n_levels - 1], detail, 0, frame);
        }
        Ok(())
    }

    fn insert(&mut self, key: ImageKey, data: Vec<f32>, up: usize, frame: u64) {
        self.images.insert(
            key,
            Entry {
                data,
                last_used: frame,
                lifetime: self.life.frames(up),
            },
        );
    }

    /// A buffer of `len` floats from the pool of evicted images (contents
    /// unspecified), or a new one.
    fn take_buffer(&mut self, len: usize) -> Vec<f32> {
        let mut v = match self.pool.iter().position(|b| b.capacity() >= len) {
            Some(i) => self.pool.swap_remove(i),
            None => Vec::with_capacity(len),
        };
        v.resize(len, 0.0);
        v
    }

    /// Decodes stream `k` and adds it into `acc` (one face, all MIPs, planar).
    fn decode_stream_add(
        &mut self,
        tex: &TextureInfo,
        view: &BlockView,
        block: usize,
        k: ImageKey,
        acc: &mut [f32],
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
        if steps.iter().all(|&s| s == 0) {
            return Ok(());
        }
        let mut r = Reader::new(bytes).ok_or(corrupt("stream is not whole words"))?;
        let mut ctx = Contexts::default();
        let mut off = 0;
        for mip in 0..l.mips {
            let (w, h) = l.mip_size(mip);
            let n = w * h * ch;
            let idx = *steps.get(mip as usize).ok_or(corrupt("missing step"))?;
            let dst = acc
                .get_mut(off..off + n)
                .ok_or(corrupt("image larger than its buffer"))?;
            if idx != 0 {
                decode_image_add(&mut r, &mut ctx, &mut self.dct, w, h, ch, step_of(idx), dst)
                    .map_err(corrupt)?;
            }
            off += n;
        }
        Ok(())
    }
}

/// Planar coding-domain image (parent prefix + leaf detail, + optional
/// MIP prediction) → interleaved linear RGBA, converted to `T` in bulk.
/// With `keep`, the planar sums (before the colour transform) are stored
/// there too: the next MIP level's prediction is decimated from them.
#[allow(clippy::too_many_arguments)]
fn write_rgba<T: OutTexel>(
    g: Gamma,
    img: [&[f32]; 2],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [T],
    keep: Option<&mut Vec<f32>>,
) {
    let keep = keep.map(|k| {
        k.clear();
        k.resize(n * ch, 0.0);
        &mut k[..]
    });
    if g.0 == 2.0 {
        write_rgba_with(|v: f32| v * v.abs(), img, pred, n, ch, out, keep)
    } else {
        write_rgba_with(|v: f32| g.inverse(v), img, pred, n, ch, out, keep)
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn write_rgba_with<T: OutTexel>(
    inv: impl Fn(f32) -> f32,
    img: [&[f32]; 2],
    pred: Option<&[f32]>,
    n: usize,
    ch: usize,
    out: &mut [T],
    mut keep: Option<&mut [f32]>,
) {
    const CHUNK: usize = 1024;
    let mut tmp = [0.0f32; CHUNK * 4];
    let mut sum = [[0.0f32; CHUNK]; 4];
    for (chunk_i, dst) in out[..n * 4].chunks_mut(CHUNK * 4).enumerate() {
        let base = chunk_i * CHUNK;
        let m = dst.len() / 4;
        // Planes (+ prediction) for this chunk, then the colour transform.
        for (c, s) in sum.iter_mut().enumerate() {
            let s = &mut s[..m];
            if c >= ch {
                s.fill(1.0);
                continue;
            }
            let (a, b) = (&img[0][c * n + base..][..m], &img[1][c * n + base..][..m]);
            s.iter_mut()
                .zip(a.iter().zip(b))
                .for_each(|(o, (x, y))| *o = x + y);
            if let Some(p) = pred {
                s.iter_mut()
                    .zip(&p[c * n + base..][..m])
                    .for_each(|(a, b)| *a += b);
            }
            if let Some(k) = keep.as_deref_mut() {
                k[c * n + base..][..m].copy_from_slice(s);
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
