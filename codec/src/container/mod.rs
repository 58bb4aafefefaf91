//! The container: one file per scene.
//!
//! ```text
//! offset  size  field                      (all little-endian)
//! 0       4     magic "PTXC"
//! 4       4     format version (FORMAT_VERSION)
//! 8       4     header_len: bytes from 0 through the header checksum
//! 12      4     n_textures
//! 16      4     n_blocks
//! 20      4     gamma (f32) of the coding domain
//! 24      1     log2 of the block size per parameter dimension (3 = 8)
//! 25      3     reserved, zero
//! 28      64×n  texture records: object, layer, width, height, faces, mips,
//!               channels, n0, n1, stagger0, stagger1, blocks0, blocks1,
//!               first_block (u32 each), screen_area (f32), reserved u32
//! ..      16×m  block index: offset u64, len u32, crc32 u32
//! ..      4     crc32 of everything above
//! ..            block payloads (anywhere after the header)
//!
//! block payload:
//!   n_levels u8, then (e0 u8, e1 u8) per level (the pyramid plan)
//!   per stream, in order (level, node, face): len u32, then one quantiser
//!     step index u8 per MIP level (0 = image not coded)
//!   stream bytes back to back (range-coded 32-bit words)
//! ```
//!
//! Texture `t`'s block `(b0, b1)` is index `first_block + b0 + blocks0·b1`;
//! parameter sample `i` of dimension `d` lies in block `(i + stagger_d) / B`.
//! Decoding a sample reads the header once, then only its block's bytes,
//! whose checksum is verified before use. Everything read from a file is
//! bounds-checked; counts that size allocations are validated against the
//! file length first.

mod block;
mod cursor;
mod header;
#[cfg(test)]
mod tests;
mod write;

pub use block::BlockView;
pub use cursor::Cursor;
pub use write::{block_table_bytes, header_bytes, reseal_checksums, write, write_block};

use std::borrow::Cow;
use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{CodecError, Result};
use crate::input::{LeafLayout, ParamGrid, TextureId};
use crate::pyramid::Plan;
use header::{parse_header, read_counts};

pub const MAGIC: [u8; 4] = *b"PTXC";
pub const FORMAT_VERSION: u32 = 1;
pub const FIXED_HEADER: usize = 28;
/// The smallest header: the fixed fields and the checksum.
pub const MIN_HEADER: usize = FIXED_HEADER + 4;
pub const TEX_RECORD: usize = 64;
pub const BLOCK_ENTRY: usize = 16;
/// Largest raw/compressed ratio a file may declare; bounds what a small
/// (possibly hostile) file can make the decoder allocate.
pub const MAX_DECLARED_RATIO: u64 = 1 << 16;
pub const BLOCK_LOG2: u8 = 3;

/// What the container says about one texture.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureInfo {
    pub id: TextureId,
    pub grid: ParamGrid,
    pub layout: LeafLayout,
    /// Block origin offset per parameter dimension (thesis §4.7 staggering).
    pub stagger: [u32; 2],
    pub blocks: [u32; 2],
    pub first_block: u32,
    pub screen_area: f32,
}

impl TextureInfo {
    /// log2 of the block extent per dimension (a 1D grid has extent 1 in dim 1).
    pub fn log2b(&self) -> [u8; 2] {
        [BLOCK_LOG2, if self.grid.n1 > 1 { BLOCK_LOG2 } else { 0 }]
    }
    pub fn block_count(&self) -> usize {
        self.blocks[0] as usize * self.blocks[1] as usize
    }
    /// Block index and position within the block of a parameter sample.
    pub fn locate(&self, sample: [u32; 2]) -> Result<(usize, [usize; 2])> {
        self.grid.index(sample)?;
        let lb = self.log2b();
        let t0 = sample[0] + self.stagger[0];
        let t1 = sample[1] + self.stagger[1];
        let b = [t0 >> lb[0], t1 >> lb[1]];
        let local = [
            (t0 & ((1 << lb[0]) - 1)) as usize,
            (t1 & ((1 << lb[1]) - 1)) as usize,
        ];
        Ok((
            self.first_block as usize + b[0] as usize + self.blocks[0] as usize * b[1] as usize,
            local,
        ))
    }
    pub fn raw_bytes(&self) -> u64 {
        self.grid.len() as u64 * self.layout.texels() as u64 * self.layout.channels as u64 * 4
    }
    /// Streams per block for a plan: one per (level, node, face).
    pub fn stream_count(&self, plan: &Plan) -> usize {
        plan.total_nodes() * self.layout.faces as usize
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockEntry {
    pub offset: u64,
    pub len: u32,
    pub crc: u32,
}

enum Source {
    Memory(Vec<u8>),
    File { file: File, path: String },
}

/// An opened, validated container. Block payloads are read on demand.
pub struct Container {
    source: Source,
    file_len: u64,
    pub gamma: f32,
    textures: Vec<TextureInfo>,
    blocks: Vec<BlockEntry>,
    bytes_read: AtomicU64,
}

impl std::fmt::Debug for Container {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Container")
            .field("file_len", &self.file_len)
            .field("textures", &self.textures.len())
            .field("blocks", &self.blocks.len())
            .finish()
    }
}

impl Container {
    /// Validates an in-memory container (header and index; block payloads
    /// are checked when first used).
    pub fn from_bytes(bytes: Vec<u8>) -> Result<Self> {
        let len = bytes.len() as u64;
        let (gamma, textures, blocks) = parse_header(&bytes, len)?;
        Ok(Self {
            source: Source::Memory(bytes),
            file_len: len,
            gamma,
            textures,
            blocks,
            bytes_read: AtomicU64::new(0),
        })
    }

    /// Opens a file, reading only its header; blocks are read when decoded.
    /// Every error names the file (so callers need not add its path again).
    pub fn open(path: &Path) -> Result<Self> {
        Self::open_file(path).map_err(|e| match e {
            CodecError::Io { .. } => e,
            e => CodecError::File {
                path: path.display().to_string(),
                cause: Box::new(e),
            },
        })
    }

    /// [`Container::open`], its errors other than i/o without the path.
    fn open_file(path: &Path) -> Result<Self> {
        let io = |cause| CodecError::Io {
            path: path.display().to_string(),
            cause,
        };
        let mut file = File::open(path).map_err(io)?;
        let file_len = file.metadata().map_err(io)?.len();
        let mut fixed = [0u8; FIXED_HEADER];
        let n = read_up_to(&mut file, &mut fixed).map_err(io)?;
        // Magic, version, and a header_len that fits the counts and the file.
        let header_len = read_counts(&fixed[..n], file_len)?.header_len;
        // header_len ≥ MIN_HEADER > FIXED_HEADER ≥ n.
        let mut header = fixed[..n].to_vec();
        header.resize(header_len as usize, 0);
        file.read_exact(&mut header[n..]).map_err(io)?;
        let (gamma, textures, blocks) = parse_header(&header, file_len)?;
        Ok(Self {
            source: Source::File {
                file,
                path: path.display().to_string(),
            },
            file_len,
            gamma,
            textures,
            blocks,
            bytes_read: AtomicU64::new(header_len),
        })
    }

    pub fn textures(&self) -> &[TextureInfo] {
        &self.textures
    }
    pub fn block_entries(&self) -> &[BlockEntry] {
        &self.blocks
    }
    pub fn file_len(&self) -> u64 {
        self.file_len
    }
    /// Bytes read from a file source so far (header included), or block
    /// bytes handed out from memory: lets tests check random access.
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read.load(Ordering::Relaxed)
    }

    pub fn texture_index(&self, object: u32, layer: u32) -> Result<usize> {
        self.textures
            .iter()
            .position(|t| t.id == TextureId { object, layer })
            .ok_or(CodecError::NoSuchTexture { object, layer })
    }

    /// One block's payload, checksum verified.
    pub fn block_bytes(&self, block: usize) -> Result<Cow<'_, [u8]>> {
        let e = *self.blocks.get(block).ok_or(CodecError::IndexOutOfRange {
            what: "block",
            got: block as u64,
            limit: self.blocks.len() as u64,
        })?;
        let bytes: Cow<[u8]> = match &self.source {
            Source::Memory(m) => {
                // Ranges were validated against the length at open.
                let s = m
                    .get(e.offset as usize..e.offset as usize + e.len as usize)
                    .ok_or(CodecError::BlockOutOfRange {
                        block,
                        offset: e.offset,
                        end: e.offset + e.len as u64,
                        start: 0,
                        len: self.file_len,
                    })?;
                Cow::Borrowed(s)
            }
            Source::File { file, path } => {
                use std::os::unix::fs::FileExt;
                let mut buf = vec![0u8; e.len as usize];
                file.read_exact_at(&mut buf, e.offset)
                    .map_err(|cause| CodecError::Io {
                        path: path.clone(),
                        cause,
                    })?;
                Cow::Owned(buf)
            }
        };
        self.bytes_read.fetch_add(e.len as u64, Ordering::Relaxed);
        let computed = crc32fast::hash(&bytes);
        if computed != e.crc {
            return Err(CodecError::BlockChecksum {
                block,
                stored: e.crc,
                computed,
            });
        }
        Ok(bytes)
    }
}

fn read_up_to(f: &mut File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}
