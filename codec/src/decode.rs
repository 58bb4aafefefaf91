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
//! The final sum, the MIP reconstruction and the inverse colour/gamma
//! transform are fused into one pass that writes the caller's slice (the
//! engine's mapped staging buffer) directly.

use std::collections::HashMap;
use std::sync::Arc;

use half::f16;

use crate::coefs::{Contexts, decode_image_add, step_of};
use crate::container::{BlockView, Container, TextureInfo};
use crate::dct::Dct8;
use crate::domain::{Gamma, from_domain};
use crate::entropy::Reader;
use crate::error::{CodecError, Result};
use crate::planes::box_down;
use crate::pyramid::Plan;

/// A texel component type the decoder can write: `f32` or `half::f16`.
pub trait OutTexel: Copy + Send {
    fn from_f32(v: f32) -> Self;
}
impl OutTexel for f32 {
    #[inline]
    fn from_f32(v: f32) -> Self {
        v
    }
}
impl OutTexel for f16 {
    #[inline]
    fn from_f32(v: f32) -> Self {
        f16::from_f32(v)
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

struct CachedBlock {
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

/// Decoded-image cache for one container. Not thread-safe by design (one
/// per decode thread); call [`DecodeCache::end_frame`] once per frame.
pub struct DecodeCache {
    life: Lifetimes,
    frame: u64,
    images: HashMap<ImageKey, Entry>,
    blocks: HashMap<usize, CachedBlock>,
    dct: Dct8,
    scratch: Vec<f32>,
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
            scratch: Vec::new(),
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
        self.images.retain(|_, e| now - e.last_used <= e.lifetime);
        self.blocks.retain(|_, b| now - b.last_used <= b.lifetime);
        self.stats.evictions += (before - self.images.len()) as u64;
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

    /// Sums the pyramid for one face up to `last_mip` and writes the MIP
    /// levels for which `dest` gives a range of `out`.
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
        let cached = self.blocks.get_mut(&block).map(|b| {
            b.last_used = frame;
            b.plan.clone()
        });
        let mut block_bytes = None;
        let plan = match cached {
            Some(p) => p,
            None => {
                let bytes = c.block_bytes(block)?;
                let plan = BlockView::parse(&bytes, tex, block)?.plan;
                self.blocks.insert(
                    block,
                    CachedBlock {
                        plan: plan.clone(),
                        last_used: frame,
                        lifetime: self.life.frames(plan.levels.len()),
                    },
                );
                block_bytes = Some(bytes);
                plan
            }
        };
        let lb = tex.log2b();
        let keys: Vec<ImageKey> = (0..plan.levels.len())
            .map(|level| ImageKey {
                block,
                level: level as u8,
                node: plan.node_of(level, local, lb) as u16,
                face: face as u8,
            })
            .collect();
        let missing: Vec<ImageKey> = keys
            .iter()
            .filter(|k| !self.images.contains_key(k))
            .copied()
            .collect();
        self.stats.hits += (keys.len() - missing.len()) as u64;
        if !missing.is_empty() {
            self.stats.misses += missing.len() as u64;
            let bytes = match block_bytes {
                Some(b) => b,
                None => c.block_bytes(block)?,
            };
            let view = BlockView::parse(&bytes, tex, block)?;
            for k in missing {
                let data = self.decode_stream(tex, &view, block, k)?;
                let up = plan.levels.len() - 1 - k.level as usize;
                self.images.insert(
                    k,
                    Entry {
                        data,
                        last_used: frame,
                        lifetime: self.life.frames(up),
                    },
                );
            }
        }
        // Sum the levels (planar, coding domain) into scratch.
        let l = &tex.layout;
        let ch = l.channels as usize;
        let face_len: usize = (0..=last_mip).map(|m| l.face_texels(m) * ch).sum();
        self.scratch.clear();
        self.scratch.resize(face_len, 0.0);
        for k in &keys {
            let e = self.images.get_mut(k).ok_or(CodecError::BadBlock {
                block,
                what: "decoded image vanished from the cache".into(),
            })?;
            e.last_used = self.frame;
            for (s, v) in self.scratch.iter_mut().zip(&e.data) {
                *s += v;
            }
        }
        // MIP 0 is the sum itself; MIP m adds the decimated finest level.
        let gamma = Gamma(c.gamma);
        let mut off = 0;
        for mip in 0..=last_mip {
            let (w, h) = l.mip_size(mip);
            let n = w * h;
            let img = &mut self.scratch[off..off + n * ch];
            if mip == 0 {
                self.pred.clear();
                self.pred.extend_from_slice(img);
            } else {
                let (pw, ph) = l.mip_size(mip - 1);
                self.pred_next.clear();
                self.pred_next.resize(n * ch, 0.0);
                box_down(&self.pred, pw, ph, ch, &mut self.pred_next);
                std::mem::swap(&mut self.pred, &mut self.pred_next);
                img.iter_mut().zip(&self.pred).for_each(|(v, p)| *v += p);
            }
            if let Some(r) = dest(mip) {
                let o = out.get_mut(r).ok_or(CodecError::OutputSize {
                    got: 0,
                    expected: n * 4,
                })?;
                write_rgba(gamma, img, n, ch, o);
            }
            off += n * ch;
        }
        Ok(())
    }

    fn decode_stream(
        &mut self,
        tex: &TextureInfo,
        view: &BlockView,
        block: usize,
        k: ImageKey,
    ) -> Result<Vec<f32>> {
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
        let total: usize = (0..l.mips).map(|m| l.face_texels(m) * ch).sum();
        let mut data = vec![0.0f32; total];
        if steps.iter().all(|&s| s == 0) {
            return Ok(data);
        }
        let mut r = Reader::new(bytes).ok_or(corrupt("stream is not whole words"))?;
        let mut ctx = Contexts::default();
        let mut off = 0;
        for mip in 0..l.mips {
            let (w, h) = l.mip_size(mip);
            let n = w * h * ch;
            let idx = *steps.get(mip as usize).ok_or(corrupt("missing step"))?;
            if idx != 0 {
                decode_image_add(
                    &mut r,
                    &mut ctx,
                    &mut self.dct,
                    w,
                    h,
                    ch,
                    step_of(idx),
                    &mut data[off..off + n],
                )
                .map_err(corrupt)?;
            }
            off += n;
        }
        Ok(data)
    }
}

/// Planar coding-domain image → interleaved linear RGBA.
fn write_rgba<T: OutTexel>(g: Gamma, img: &[f32], n: usize, ch: usize, out: &mut [T]) {
    let (y, rest) = img.split_at(n);
    let (co, rest) = rest.split_at(n);
    let (cg, alpha) = rest.split_at(n);
    for (i, px) in out.chunks_exact_mut(4).enumerate().take(n) {
        let a = if ch == 4 { alpha[i] } else { 1.0 };
        let rgba = from_domain(g, y[i], co[i], cg[i], a);
        px[0] = T::from_f32(rgba[0]);
        px[1] = T::from_f32(rgba[1]);
        px[2] = T::from_f32(rgba[2]);
        px[3] = T::from_f32(rgba[3]);
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
