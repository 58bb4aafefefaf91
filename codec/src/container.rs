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

use std::borrow::Cow;
use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{CodecError, Result};
use crate::input::{LeafLayout, MAX_DIM, MAX_SAMPLES, MAX_SAMPLES_PER_DIM, ParamGrid, TextureId};
use crate::pyramid::Plan;

pub const MAGIC: [u8; 4] = *b"PTXC";
pub const FORMAT_VERSION: u32 = 1;
pub const FIXED_HEADER: usize = 28;
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

/// Bounds-checked little-endian reads with field names for errors.
pub struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    base: u64,
}

impl<'a> Cursor<'a> {
    pub fn new(bytes: &'a [u8], base: u64) -> Self {
        Self {
            bytes,
            pos: 0,
            base,
        }
    }
    pub fn take(&mut self, n: usize, field: &'static str) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(CodecError::Truncated {
                field,
                offset: self.base + self.pos as u64,
                needed: n as u64,
                len: self.base + self.bytes.len() as u64,
            });
        };
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    pub fn u8(&mut self, field: &'static str) -> Result<u8> {
        Ok(self.take(1, field)?[0])
    }
    pub fn u32(&mut self, field: &'static str) -> Result<u32> {
        let b = self.take(4, field)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    pub fn u64(&mut self, field: &'static str) -> Result<u64> {
        let lo = self.u32(field)? as u64;
        let hi = self.u32(field)? as u64;
        Ok(lo | (hi << 32))
    }
    pub fn pos(&self) -> usize {
        self.pos
    }
    pub fn rest(&self) -> &'a [u8] {
        &self.bytes[self.pos..]
    }
}

fn bad(field: &'static str, got: u64, expected: impl Into<String>) -> CodecError {
    CodecError::BadField {
        field,
        got,
        expected: expected.into(),
    }
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
    pub fn open(path: &Path) -> Result<Self> {
        let io = |source| CodecError::Io {
            path: path.display().to_string(),
            source,
        };
        let mut file = File::open(path).map_err(io)?;
        let file_len = file.metadata().map_err(io)?.len();
        let mut fixed = [0u8; FIXED_HEADER];
        let n = read_up_to(&mut file, &mut fixed).map_err(io)?;
        // Let the parser report truncation/magic/version on the fixed part.
        let header_len = {
            let mut c = Cursor::new(&fixed[..n], 0);
            check_magic_version(&mut c)?;
            c.u32("header_len")? as u64
        };
        if header_len > file_len || header_len < FIXED_HEADER as u64 + 4 {
            return Err(bad(
                "header_len",
                header_len,
                format!("{}..={file_len}", FIXED_HEADER + 4),
            ));
        }
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
                    .map_err(|source| CodecError::Io {
                        path: path.clone(),
                        source,
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

fn check_magic_version(c: &mut Cursor) -> Result<()> {
    let m = c.take(4, "magic")?;
    let got = [m[0], m[1], m[2], m[3]];
    if got != MAGIC {
        return Err(CodecError::BadMagic {
            got,
            expected: MAGIC,
        });
    }
    let v = c.u32("version")?;
    if v != FORMAT_VERSION {
        return Err(CodecError::VersionMismatch {
            got: v,
            expected: FORMAT_VERSION,
        });
    }
    Ok(())
}

type Header = (f32, Vec<TextureInfo>, Vec<BlockEntry>);

/// Parses and validates the header. `header` starts at file offset 0 and
/// holds at least the whole header; `file_len` is the full file's length.
fn parse_header(header: &[u8], file_len: u64) -> Result<Header> {
    let mut c = Cursor::new(header, 0);
    check_magic_version(&mut c)?;
    let header_len = c.u32("header_len")? as u64;
    let nt = c.u32("n_textures")? as u64;
    let nb = c.u32("n_blocks")? as u64;
    let expected_len = FIXED_HEADER as u64 + TEX_RECORD as u64 * nt + BLOCK_ENTRY as u64 * nb + 4;
    if header_len != expected_len {
        return Err(bad(
            "header_len",
            header_len,
            format!("{expected_len} for {nt} textures and {nb} blocks"),
        ));
    }
    if header_len > file_len || header_len > header.len() as u64 {
        return Err(CodecError::Truncated {
            field: "header",
            offset: 0,
            needed: header_len,
            len: file_len.min(header.len() as u64),
        });
    }
    let stored_crc = {
        let t = &header[header_len as usize - 4..header_len as usize];
        u32::from_le_bytes([t[0], t[1], t[2], t[3]])
    };
    let computed = crc32fast::hash(&header[..header_len as usize - 4]);
    if stored_crc != computed {
        return Err(CodecError::HeaderChecksum {
            stored: stored_crc,
            computed,
        });
    }
    if nt == 0 {
        return Err(bad("n_textures", 0, "at least 1"));
    }
    let gamma = f32::from_bits(c.u32("gamma")?);
    if !(gamma.is_finite() && (1.0..=4.0).contains(&gamma)) {
        return Err(bad(
            "gamma",
            gamma.to_bits() as u64,
            "a finite value in 1..=4",
        ));
    }
    let log2 = c.u8("block_log2")?;
    if log2 != BLOCK_LOG2 {
        return Err(bad("block_log2", log2 as u64, BLOCK_LOG2.to_string()));
    }
    c.take(3, "reserved")?;

    let mut textures = Vec::with_capacity(nt as usize);
    let mut next_block = 0u64;
    let mut raw = 0u64;
    for _ in 0..nt {
        let t = parse_texture(&mut c, next_block)?;
        next_block += t.block_count() as u64;
        raw = raw.saturating_add(t.raw_bytes());
        if textures.iter().any(|o: &TextureInfo| o.id == t.id) {
            return Err(bad(
                "texture id",
                t.id.object as u64,
                "unique (object, layer) pairs",
            ));
        }
        textures.push(t);
    }
    if next_block != nb {
        return Err(bad(
            "n_blocks",
            nb,
            format!("{next_block} (sum of the textures' blocks)"),
        ));
    }
    if raw > file_len.saturating_mul(MAX_DECLARED_RATIO) {
        return Err(CodecError::ImplausibleSize {
            declared: raw,
            file_len,
            max_ratio: MAX_DECLARED_RATIO,
        });
    }
    let mut blocks = Vec::with_capacity(nb as usize);
    for i in 0..nb as usize {
        let offset = c.u64("block offset")?;
        let len = c.u32("block len")?;
        let crc = c.u32("block crc")?;
        let end = offset.checked_add(len as u64);
        if offset < header_len || end.is_none_or(|e| e > file_len) {
            return Err(CodecError::BlockOutOfRange {
                block: i,
                offset,
                end: end.unwrap_or(u64::MAX),
                start: header_len,
                len: file_len,
            });
        }
        blocks.push(BlockEntry { offset, len, crc });
    }
    Ok((gamma, textures, blocks))
}

fn parse_texture(c: &mut Cursor, first_expected: u64) -> Result<TextureInfo> {
    let mut f = [0u32; 16];
    for (v, name) in f.iter_mut().zip([
        "object",
        "layer",
        "width",
        "height",
        "faces",
        "mips",
        "channels",
        "n0",
        "n1",
        "stagger0",
        "stagger1",
        "blocks0",
        "blocks1",
        "first_block",
        "screen_area",
        "reserved",
    ]) {
        *v = c.u32(name)?;
    }
    let [
        object,
        layer,
        width,
        height,
        faces,
        mips,
        channels,
        n0,
        n1,
        s0,
        s1,
        b0,
        b1,
        first,
        area,
        _,
    ] = f;
    let range = |field, v: u32, lo: u32, hi: u32| {
        if v < lo || v > hi {
            Err(bad(field, v as u64, format!("{lo}..={hi}")))
        } else {
            Ok(())
        }
    };
    range("width", width, 1, MAX_DIM)?;
    range("height", height, 1, MAX_DIM)?;
    if faces != 1 && faces != 6 {
        return Err(bad("faces", faces as u64, "1 or 6"));
    }
    range("mips", mips, 1, LeafLayout::max_mips(width, height))?;
    range("channels", channels, 3, 4)?;
    range("n0", n0, 1, MAX_SAMPLES_PER_DIM)?;
    range("n1", n1, 1, MAX_SAMPLES_PER_DIM)?;
    if n0 as u64 * n1 as u64 > MAX_SAMPLES {
        return Err(bad(
            "n0*n1",
            n0 as u64 * n1 as u64,
            format!("at most {MAX_SAMPLES}"),
        ));
    }
    let bsz = 1u32 << BLOCK_LOG2;
    range("stagger0", s0, 0, bsz - 1)?;
    range("stagger1", s1, 0, if n1 > 1 { bsz - 1 } else { 0 })?;
    let t = TextureInfo {
        id: TextureId { object, layer },
        grid: ParamGrid { n0, n1 },
        layout: LeafLayout {
            width,
            height,
            faces,
            mips,
            channels,
        },
        stagger: [s0, s1],
        blocks: [b0, b1],
        first_block: first,
        screen_area: f32::from_bits(area),
    };
    let lb = t.log2b();
    let want = [
        (n0 + s0).div_ceil(1 << lb[0]),
        (n1 + s1).div_ceil(1 << lb[1]),
    ];
    if [b0, b1] != want {
        return Err(bad(
            "blocks0/blocks1",
            b0 as u64,
            format!("{want:?} for the grid and stagger"),
        ));
    }
    if first as u64 != first_expected {
        return Err(bad("first_block", first as u64, first_expected.to_string()));
    }
    if !(t.screen_area.is_finite() && t.screen_area >= 0.0) {
        return Err(bad("screen_area", area as u64, "finite and non-negative"));
    }
    Ok(t)
}

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
