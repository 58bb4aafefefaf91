//! Decoding ahead along the path. A leaf whose block or coarser pyramid node
//! is new to the cache decodes those levels itself: along the teapot's
//! orbit every eighth leaf took 3–3.5 ms against 0.8–1 ms for the others,
//! and those leaves were the decode's p95. Playback moves along its path,
//! so the cache remembers each texture's last samples and, when the eye
//! moved by the same step twice, [`DecodeCache::warm_ahead`] decodes about
//! a sample's share of the coarse levels the next samples will need:
//! the block-boundary work spreads over the frames before it. Leaf images
//! are never warmed (every sample needs its own anyway), and a guess that
//! does not come true costs only its budget: the images age out of the
//! cache like any other.

use super::{DecodeCache, ImageKey};
use crate::container::{BLOCK_LOG2, BlockView, Container, TextureInfo};
use crate::error::{CodecError, Result};

/// Samples ahead of the eye that [`DecodeCache::warm_ahead`] looks at: one
/// block along an axis, so a new block's levels are ready when it starts.
pub const LOOKAHEAD: i64 = 1 << BLOCK_LOG2;

/// A texture's last three distinct samples, newest last.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Motion {
    seen: [Option<[u32; 2]>; 3],
}

impl Motion {
    pub(super) fn note(&mut self, sample: [u32; 2]) {
        if self.seen[2] != Some(sample) {
            self.seen = [self.seen[1], self.seen[2], Some(sample)];
        }
    }

    /// The newest sample and the step that led to it, when the two last
    /// steps were the same (a path, not a blend alternating its samples).
    fn steady(&self) -> Option<([u32; 2], [i64; 2])> {
        let [Some(a), Some(b), Some(c)] = self.seen else {
            return None;
        };
        let step =
            |p: [u32; 2], q: [u32; 2]| [q[0] as i64 - p[0] as i64, q[1] as i64 - p[1] as i64];
        let (s1, s2) = (step(a, b), step(b, c));
        (s1 == s2).then_some((c, s2))
    }
}

impl DecodeCache {
    /// Decodes coarse level images (every level above the leaves) that the
    /// next [`LOOKAHEAD`] samples along the texture's steady motion need
    /// and the cache does not hold, nearest sample first and each face's
    /// coarsest level first, until their streams add up to a sample's
    /// share of the block's coarse bytes (× 5/4, to catch up after a
    /// turn); returns how many images it decoded. Bytes, not images: a
    /// root image costs several times a finer one. Does nothing until the
    /// texture's last two steps agree.
    pub fn warm_ahead(&mut self, c: &Container, object: u32, layer: u32) -> Result<usize> {
        let ti = c.texture_index(object, layer)?;
        let tex = &c.textures()[ti];
        let Some((now, step)) = self.motion.get(&ti).and_then(Motion::steady) else {
            return Ok(0);
        };
        let (mut done, mut spent, mut budget) = (0, 0, None);
        for k in 1..=LOOKAHEAD {
            let s = [now[0] as i64 + k * step[0], now[1] as i64 + k * step[1]];
            let inside = |v: i64, n: u32| (0..n as i64).contains(&v);
            if !inside(s[0], tex.grid.n0) || !inside(s[1], tex.grid.n1) {
                break;
            }
            let (block, local) = tex.locate([s[0] as u32, s[1] as u32])?;
            let paths = (0..tex.layout.faces)
                .map(|face| self.level_path(c, tex, block, local, face))
                .collect::<Result<Vec<_>>>()?;
            // Every level but the leaf, face by face, coarsest first.
            let missing: Vec<(usize, usize)> = (paths.iter().enumerate())
                .flat_map(|(f, p)| (0..p.len().saturating_sub(1)).map(move |l| (f, l)))
                .filter(|&(f, l)| !self.images.contains_key(&paths[f][l]))
                .collect();
            if missing.is_empty() {
                continue;
            }
            let sizes = self.stream_sizes(tex, block, &paths)?;
            let budget = *budget.get_or_insert(sizes.share * 5 / 4);
            let mut levels = vec![Vec::new(); paths.len()];
            let mut spent_all = false;
            for (f, l) in missing {
                if budget > 0 && spent >= budget {
                    spent_all = true;
                    break;
                }
                levels[f].push(l);
                spent += sizes.paths[f][l];
            }
            for (path, levels) in paths.iter().zip(&levels) {
                if !levels.is_empty() {
                    self.decode_path_levels(tex, block, path, levels)?;
                }
                done += levels.len();
                self.stats.warmed += levels.len() as u64;
            }
            if spent_all {
                return Ok(done);
            }
        }
        Ok(done)
    }

    /// The coded bytes of each image of `paths` (one block's) and the
    /// block's coarse bytes per leaf sample (the block cached by
    /// `level_path`).
    fn stream_sizes(
        &self,
        tex: &TextureInfo,
        block: usize,
        paths: &[Vec<ImageKey>],
    ) -> Result<Sizes> {
        let cb = self.blocks.get(&block).ok_or(CodecError::BadBlock {
            block,
            what: "block vanished from the cache".into(),
        })?;
        let view = BlockView::parse(&cb.bytes, tex, block)?;
        let plan = &view.plan;
        let len = |k: &ImageKey| {
            let si = BlockView::stream_index(
                plan,
                tex.layout.faces,
                k.level as usize,
                k.node as usize,
                k.face as u32,
            );
            view.streams.get(si).map_or(0, |(_, b)| b.len())
        };
        // Streams run level by level: the coarse ones come first.
        let leaves = plan.levels.len().checked_sub(1).map(|l| plan.node_count(l));
        let coarse_streams = (plan.total_nodes() - leaves.unwrap_or(0)) * tex.layout.faces as usize;
        let coarse_bytes: usize = view
            .streams
            .iter()
            .take(coarse_streams)
            .map(|(_, b)| b.len())
            .sum();
        Ok(Sizes {
            paths: paths.iter().map(|p| p.iter().map(len).collect()).collect(),
            share: coarse_bytes / leaves.unwrap_or(1).max(1),
        })
    }
}

/// What [`DecodeCache::stream_sizes`] finds.
struct Sizes {
    paths: Vec<Vec<usize>>,
    share: usize,
}
