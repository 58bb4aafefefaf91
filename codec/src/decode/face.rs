//! Decoding one face of a leaf: the block and its level images, from the
//! cache or the stream, summed and written by [`super::mips`].

use super::{CachedBlock, DecodeCache, Entry, ImageKey, LeafSink, OutTexel};
use crate::coefs::{Contexts, decode_image, step_of};
use crate::container::{BlockView, Container, TextureInfo};
use crate::dct::Dct8;
use crate::domain::Gamma;
use crate::entropy::Reader;
use crate::error::{CodecError, Result};
use crate::sparse::SparseImage;

impl DecodeCache {
    /// Finds or decodes the level images of one face's path, sums them,
    /// then writes the MIP levels `sink` asks for.
    pub(super) fn decode_face<T: OutTexel>(
        &mut self,
        c: &Container,
        tex: &TextureInfo,
        (sample, face): ([u32; 2], u32),
        last_mip: u32,
        sink: &mut impl LeafSink<T>,
    ) -> Result<()> {
        let (block, local) = tex.locate(sample)?;
        let path = self.level_path(c, tex, block, local, face)?;
        self.ensure_levels(tex, block, &path)?;
        let vanished = || CodecError::BadBlock {
            block,
            what: "decoded image vanished from the cache".into(),
        };
        let levels = path
            .iter()
            .map(|k| self.images.get(k).map(|e| &e.data))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(vanished)?;
        let gamma = Gamma(c.gamma);
        self.scratch
            .write_mips(gamma, &tex.layout, &levels, last_mip, face, sink)
    }

    /// The image keys of `local`'s path through the block's pyramid, root
    /// first; reads and parses the block if it is not cached.
    pub(super) fn level_path(
        &mut self,
        c: &Container,
        tex: &TextureInfo,
        block: usize,
        local: [usize; 2],
        face: u32,
    ) -> Result<Vec<ImageKey>> {
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
        Ok((0..n_levels)
            .map(|level| ImageKey {
                block,
                level: level as u8,
                node: cb.plan.node_of(level, local, lb) as u16,
                face: face as u8,
            })
            .collect())
    }

    /// Marks the cached images of `path` used and decodes the others.
    fn ensure_levels(&mut self, tex: &TextureInfo, block: usize, path: &[ImageKey]) -> Result<()> {
        let frame = self.frame;
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
        if missing.is_empty() {
            return Ok(());
        }
        self.stats.misses += missing.len() as u64;
        self.decode_path_levels(tex, block, path, &missing)
    }

    /// Decodes and caches `path[level]` for each of `levels` from the
    /// cached block's bytes (see [`Self::level_path`]).
    pub(super) fn decode_path_levels(
        &mut self,
        tex: &TextureInfo,
        block: usize,
        path: &[ImageKey],
        levels: &[usize],
    ) -> Result<()> {
        // Take the bytes out while decoding (the decoder borrows self).
        let bytes = self
            .blocks
            .get_mut(&block)
            .map(|b| std::mem::take(&mut b.bytes))
            .unwrap_or_default();
        let result = self.decode_levels(tex, &bytes, block, path, levels);
        if let Some(b) = self.blocks.get_mut(&block) {
            b.bytes = bytes;
        }
        result
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
