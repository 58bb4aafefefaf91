//! Where each texture's parameter blocks go: staggered origins (thesis
//! §4.7) and block counts.

use super::EncodeOptions;
use crate::container::{BLOCK_LOG2, TextureInfo};
use crate::input::EncodeInput;

/// Staggered block origin for the `rank`-th of `n` objects.
fn stagger_for(rank: usize, n: usize, samples: u32) -> u32 {
    let b = 1usize << BLOCK_LOG2;
    if samples as usize <= b || n <= 1 {
        return 0;
    }
    ((rank * b / n.min(b)) % b) as u32
}

pub(super) fn texture_infos(input: &EncodeInput, opts: &EncodeOptions) -> Vec<TextureInfo> {
    let mut objects: Vec<u32> = input.textures.iter().map(|t| t.id.object).collect();
    objects.sort();
    objects.dedup();
    let mut first = 0u32;
    input
        .textures
        .iter()
        .map(|t| {
            let rank = objects.binary_search(&t.id.object).unwrap_or(0);
            let s = |n| {
                if opts.stagger {
                    stagger_for(rank, objects.len(), n)
                } else {
                    0
                }
            };
            let stagger = [s(t.grid.n0), if t.grid.n1 > 1 { s(t.grid.n1) } else { 0 }];
            let mut info = TextureInfo {
                id: t.id,
                grid: t.grid,
                layout: t.layout,
                stagger,
                blocks: [0, 0],
                first_block: first,
                screen_area: t.screen_area,
            };
            let lb = info.log2b();
            info.blocks = [
                (t.grid.n0 + stagger[0]).div_ceil(1 << lb[0]),
                (t.grid.n1 + stagger[1]).div_ceil(1 << lb[1]),
            ];
            first += info.block_count() as u32;
            info
        })
        .collect()
}
