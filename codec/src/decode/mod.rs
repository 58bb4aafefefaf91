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

mod ahead;
mod face;
mod mips;
mod texel;

pub use ahead::LOOKAHEAD;
pub use texel::OutTexel;

use std::collections::HashMap;
use std::sync::Arc;

use crate::container::Container;
use crate::dct::Dct8;
use crate::error::{CodecError, Result};
use crate::pyramid::Plan;
use crate::sparse::SparseImage;
use ahead::Motion;
use mips::Scratch;

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
    /// Level images decoded ahead of need ([`DecodeCache::warm_ahead`]).
    pub warmed: u64,
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
    scratch: Scratch,
    stats: CacheStats,
    /// Each texture's last samples (by texture index), for warming ahead.
    motion: HashMap<usize, Motion>,
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
            scratch: Scratch::default(),
            stats: CacheStats::default(),
            motion: HashMap::new(),
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
        self.motion.clear();
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
        let layout = tex.layout;
        let mut sink = RangeSink {
            out,
            dest: |face, mip| {
                let o = layout.texel_offset(face, mip) * 4;
                Some(o..o + layout.face_texels(mip) * 4)
            },
        };
        self.decode_leaf_into(c, object, layer, sample, &mut sink)
    }

    /// Decodes the whole leaf of one parameter sample — every face and MIP
    /// level — into `sink`, level by level (texels as
    /// [`Self::decode_leaf_all`] writes them, one face and MIP at a time):
    /// for a caller whose memory is not one tight leaf, e.g. a texture
    /// whose rows are padded.
    pub fn decode_leaf_into<T: OutTexel>(
        &mut self,
        c: &Container,
        object: u32,
        layer: u32,
        sample: [u32; 2],
        sink: &mut impl LeafSink<T>,
    ) -> Result<()> {
        let ti = c.texture_index(object, layer)?;
        let tex = &c.textures()[ti];
        self.motion.entry(ti).or_default().note(sample);
        for face in 0..tex.layout.faces {
            self.decode_face(c, tex, (sample, face), tex.layout.mips - 1, sink)?;
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
        self.motion.entry(ti).or_default().note(sample);
        let mut sink = RangeSink {
            out,
            dest: |_, m| (m == mip).then_some(0..expected),
        };
        self.decode_face(c, tex, (sample, face), mip, &mut sink)
    }
}

/// Where a leaf's decoded texels go, one face and MIP level at a time.
pub trait LeafSink<T> {
    /// The tight RGBA slice (`texels × 4` components, rows top to bottom)
    /// `face`'s MIP level `mip` is written into; None when that level is
    /// not wanted.
    fn level(&mut self, face: u32, mip: u32, texels: usize) -> Option<&mut [T]>;
}

/// A sink inside one slice: `dest` gives each wanted level's range.
struct RangeSink<'a, T, F> {
    out: &'a mut [T],
    dest: F,
}

impl<T, F: Fn(u32, u32) -> Option<std::ops::Range<usize>>> LeafSink<T> for RangeSink<'_, T, F> {
    fn level(&mut self, face: u32, mip: u32, _texels: usize) -> Option<&mut [T]> {
        // A range outside `out` gives an empty slice: the caller then
        // reports the size it expected.
        (self.dest)(face, mip).map(|r| self.out.get_mut(r).unwrap_or_default())
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
