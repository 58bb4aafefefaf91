//! Parsing one block's payload: its pyramid plan and stream table.

use super::{Cursor, TextureInfo};
use crate::error::{CodecError, Result};
use crate::pyramid::Plan;

/// A parsed block: the pyramid plan and where each stream's bytes are.
pub struct BlockView<'a> {
    pub plan: Plan,
    /// Per stream (level, node, face): step index per MIP and its bytes.
    pub streams: Vec<(&'a [u8], &'a [u8])>,
}

impl<'a> BlockView<'a> {
    pub fn parse(bytes: &'a [u8], tex: &TextureInfo, block: usize) -> Result<Self> {
        let bad_block = |what: String| CodecError::BadBlock { block, what };
        let mut c = Cursor::new(bytes, 0);
        let n_levels = c.u8("n_levels")? as usize;
        let lb = tex.log2b();
        if n_levels == 0 || n_levels > (lb[0] + lb[1] + 1) as usize {
            return Err(bad_block(format!(
                "{n_levels} pyramid levels for block size 2^{lb:?}"
            )));
        }
        let mut levels = Vec::with_capacity(n_levels);
        for _ in 0..n_levels {
            let e = c.take(2, "level exponents")?;
            levels.push([e[0], e[1]]);
        }
        let plan = Plan { levels };
        if !plan.is_valid(lb) {
            return Err(bad_block(format!("invalid pyramid plan {:?}", plan.levels)));
        }
        let n_streams = tex.stream_count(&plan);
        let mips = tex.layout.mips as usize;
        let mut table = Vec::with_capacity(n_streams);
        for _ in 0..n_streams {
            let len = c.u32("stream len")? as usize;
            let steps = c.take(mips, "stream steps")?;
            table.push((len, steps));
        }
        let mut rest = c.rest();
        let mut streams = Vec::with_capacity(n_streams);
        for (i, (len, steps)) in table.into_iter().enumerate() {
            if len > rest.len() {
                return Err(bad_block(format!(
                    "stream {i} declares {len} bytes, {} remain",
                    rest.len()
                )));
            }
            if len % 4 != 0 {
                return Err(bad_block(format!(
                    "stream {i} length {len} is not whole words"
                )));
            }
            let (s, r) = rest.split_at(len);
            streams.push((steps, s));
            rest = r;
        }
        if !rest.is_empty() {
            return Err(bad_block(format!("{} trailing bytes", rest.len())));
        }
        Ok(Self { plan, streams })
    }

    /// Stream index of `(level, node, face)`.
    pub fn stream_index(plan: &Plan, faces: u32, level: usize, node: usize, face: u32) -> usize {
        let before: usize = (0..level).map(|l| plan.node_count(l)).sum();
        (before + node) * faces as usize + face as usize
    }
}
