//! Serialising containers and blocks (see the module doc of
//! [`super`] for the layout), their sizes, and resealing checksums.

use super::{
    BLOCK_ENTRY, BLOCK_LOG2, FIXED_HEADER, FORMAT_VERSION, MAGIC, TEX_RECORD, TextureInfo,
};
use crate::pyramid::Plan;

/// Serialises a container; `blocks` in index order.
pub fn write(gamma: f32, textures: &[TextureInfo], blocks: &[Vec<u8>]) -> Vec<u8> {
    let header_len = FIXED_HEADER + TEX_RECORD * textures.len() + BLOCK_ENTRY * blocks.len() + 4;
    let total = header_len + blocks.iter().map(Vec::len).sum::<usize>();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&MAGIC);
    for v in [
        FORMAT_VERSION,
        header_len as u32,
        textures.len() as u32,
        blocks.len() as u32,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&gamma.to_le_bytes());
    out.extend_from_slice(&[BLOCK_LOG2, 0, 0, 0]);
    for t in textures {
        let l = &t.layout;
        for v in [
            t.id.object,
            t.id.layer,
            l.width,
            l.height,
            l.faces,
            l.mips,
            l.channels,
            t.grid.n0,
            t.grid.n1,
            t.stagger[0],
            t.stagger[1],
            t.blocks[0],
            t.blocks[1],
            t.first_block,
            t.screen_area.to_bits(),
            0,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let mut offset = header_len as u64;
    for b in blocks {
        out.extend_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(b).to_le_bytes());
        offset += b.len() as u64;
    }
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    for b in blocks {
        out.extend_from_slice(b);
    }
    out
}

/// Serialises one block (see the module doc); `streams` in stream order.
pub fn write_block(plan: &Plan, streams: &[(Vec<u8>, Vec<u8>)]) -> Vec<u8> {
    let mut out = vec![plan.levels.len() as u8];
    for e in &plan.levels {
        out.extend_from_slice(e);
    }
    for (steps, bytes) in streams {
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(steps);
    }
    for (_, bytes) in streams {
        out.extend_from_slice(bytes);
    }
    out
}

/// Header bytes for a container of these textures (blocks included).
pub fn header_bytes(n_textures: usize, n_blocks: usize) -> u64 {
    (FIXED_HEADER + TEX_RECORD * n_textures + BLOCK_ENTRY * n_blocks + 4) as u64
}

/// Bytes of a block's own tables (plan and stream table), without streams.
pub fn block_table_bytes(tex: &TextureInfo, plan: &Plan) -> u64 {
    (1 + 2 * plan.levels.len() + tex.stream_count(plan) * (4 + tex.layout.mips as usize)) as u64
}

/// Recomputes the header checksum and every in-range block checksum in
/// place. For fuzzing and tests only: lets mutated files reach the
/// structural checks and the entropy decoder behind the checksums.
pub fn reseal_checksums(bytes: &mut [u8]) {
    let rd = |b: &[u8], at: usize| -> Option<u64> {
        let s = b.get(at..at + 4)?;
        Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as u64)
    };
    let (Some(header_len), Some(nt), Some(nb)) = (rd(bytes, 8), rd(bytes, 12), rd(bytes, 16))
    else {
        return;
    };
    let index = FIXED_HEADER as u64 + TEX_RECORD as u64 * nt;
    let len = bytes.len() as u64;
    for i in 0..nb {
        let at = index + BLOCK_ENTRY as u64 * i;
        if at + BLOCK_ENTRY as u64 > len.min(header_len) {
            break;
        }
        let at = at as usize;
        let (Some(lo), Some(hi), Some(bl)) = (rd(bytes, at), rd(bytes, at + 4), rd(bytes, at + 8))
        else {
            break;
        };
        let off = lo | (hi << 32);
        if let Some(end) = off.checked_add(bl).filter(|&e| e <= len) {
            let crc = crc32fast::hash(&bytes[off as usize..end as usize]);
            bytes[at + 12..at + 16].copy_from_slice(&crc.to_le_bytes());
        }
    }
    if header_len >= 4 && header_len <= len {
        let h = header_len as usize;
        let crc = crc32fast::hash(&bytes[..h - 4]);
        bytes[h - 4..h].copy_from_slice(&crc.to_le_bytes());
    }
}
