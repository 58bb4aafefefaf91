//! Parsing and validating the container header: fixed fields, texture
//! records and the block index, each checked against the file's length.

use super::{
    BLOCK_ENTRY, BLOCK_LOG2, BlockEntry, Cursor, FIXED_HEADER, FORMAT_VERSION, MAGIC,
    MAX_DECLARED_RATIO, MIN_HEADER, TEX_RECORD, TextureInfo,
};
use crate::error::{CodecError, Implied, Result};
use crate::input::{LeafLayout, MAX_DIM, MAX_SAMPLES, MAX_SAMPLES_PER_DIM, ParamGrid, TextureId};

pub(super) fn bad(field: &'static str, got: u64, expected: impl Into<String>) -> CodecError {
    CodecError::BadField {
        field,
        got,
        expected: expected.into(),
    }
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

/// Parses and validates the header. `bytes` starts at file offset 0 and
/// holds at least the whole header; `file_len` is the full file's length.
pub(super) fn parse_header(bytes: &[u8], file_len: u64) -> Result<Header> {
    let Counts { header_len, nt, nb } = read_counts(bytes, file_len)?;
    let header = bytes
        .get(..header_len as usize)
        .ok_or(CodecError::TruncatedFile {
            len: bytes.len() as u64,
            implied: Implied::Header(header_len),
        })?;
    check_checksum(header)?;
    if nt == 0 {
        return Err(bad("n_textures", 0, "at least 1"));
    }
    let mut c = Cursor::new(header, 0);
    c.take(COUNTS_END, "counts")?; // read by read_counts
    let gamma = parse_coding_domain(&mut c)?;
    let textures = parse_textures(&mut c, nt, nb, file_len)?;
    let blocks = parse_block_index(&mut c, nb, header_len, file_len)?;
    Ok((gamma, textures, blocks))
}

/// The header's length and its texture and block counts.
pub(super) struct Counts {
    pub(super) header_len: u64,
    nt: u64,
    nb: u64,
}

/// Where the counts end: magic, version, header_len, n_textures, n_blocks.
const COUNTS_END: usize = 20;

/// Magic, version and counts from the file's first bytes (`fixed`; all of
/// them when the file is shorter than the fixed header), checked against
/// the file's length `file_len`. A `header_len` below the smallest header
/// or other than its counts imply is corrupt; one that fits its counts but
/// not the file means the file was cut off ([`CodecError::TruncatedFile`]).
pub(super) fn read_counts(fixed: &[u8], file_len: u64) -> Result<Counts> {
    let too_short = || CodecError::TruncatedFile {
        len: file_len,
        implied: Implied::MinimumHeader,
    };
    let mut c = Cursor::new(fixed, 0);
    match check_magic_version(&mut c) {
        Err(CodecError::Truncated { .. }) => return Err(too_short()),
        r => r?,
    }
    let header_len = c.u32("header_len").map_err(|_| too_short())? as u64;
    if header_len < MIN_HEADER as u64 {
        return Err(bad(
            "header_len",
            header_len,
            format!("at least {MIN_HEADER}"),
        ));
    }
    let cut = CodecError::TruncatedFile {
        len: file_len,
        implied: Implied::Header(header_len),
    };
    let (Ok(nt), Ok(nb)) = (c.u32("n_textures"), c.u32("n_blocks")) else {
        // Shorter than the counts, so than any header_len ≥ MIN_HEADER.
        return Err(cut);
    };
    let (nt, nb) = (nt as u64, nb as u64);
    let expected_len = FIXED_HEADER as u64 + TEX_RECORD as u64 * nt + BLOCK_ENTRY as u64 * nb + 4;
    if header_len != expected_len {
        return Err(bad(
            "header_len",
            header_len,
            format!("{expected_len} for {nt} textures and {nb} blocks"),
        ));
    }
    if header_len > file_len {
        return Err(cut);
    }
    Ok(Counts { header_len, nt, nb })
}

/// The checksum in the last 4 bytes of `header` against the bytes before.
fn check_checksum(header: &[u8]) -> Result<()> {
    let Some((body, tail)) = header.split_last_chunk::<4>() else {
        return Err(bad(
            "header_len",
            header.len() as u64,
            format!("at least {MIN_HEADER}"),
        ));
    };
    let stored = u32::from_le_bytes(*tail);
    let computed = crc32fast::hash(body);
    if stored != computed {
        return Err(CodecError::HeaderChecksum { stored, computed });
    }
    Ok(())
}

/// The coding domain's gamma, after checking the block size and the
/// reserved bytes.
fn parse_coding_domain(c: &mut Cursor) -> Result<f32> {
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
    Ok(gamma)
}

/// The `nt` texture records: unique ids, blocks adding up to `nb`, and a
/// raw size plausible for the file's length.
fn parse_textures(c: &mut Cursor, nt: u64, nb: u64, file_len: u64) -> Result<Vec<TextureInfo>> {
    let mut textures = Vec::with_capacity(nt as usize);
    let mut next_block = 0u64;
    let mut raw = 0u64;
    for _ in 0..nt {
        let t = parse_texture(c, next_block)?;
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
    Ok(textures)
}

/// The `nb` block index entries, each after the header and inside the
/// file: an entry that overlaps the header or ends past any file's end is
/// corrupt; the one ending last ending past this file's end means the
/// file was cut off ([`CodecError::TruncatedFile`]).
fn parse_block_index(
    c: &mut Cursor,
    nb: u64,
    header_len: u64,
    file_len: u64,
) -> Result<Vec<BlockEntry>> {
    let mut blocks = Vec::with_capacity(nb as usize);
    // The block that ends last, and its end.
    let mut last: Option<(usize, u64)> = None;
    for i in 0..nb as usize {
        let offset = c.u64("block offset")?;
        let len = c.u32("block len")?;
        let crc = c.u32("block crc")?;
        let end = offset.checked_add(len as u64);
        let Some(end) = end.filter(|_| offset >= header_len) else {
            return Err(CodecError::BlockOutOfRange {
                block: i,
                offset,
                end: end.unwrap_or(u64::MAX),
                start: header_len,
                len: file_len,
            });
        };
        if last.is_none_or(|(_, e)| end > e) {
            last = Some((i, end));
        }
        blocks.push(BlockEntry { offset, len, crc });
    }
    if let Some((block, end)) = last.filter(|&(_, end)| end > file_len) {
        return Err(CodecError::TruncatedFile {
            len: file_len,
            implied: Implied::Block { block, end },
        });
    }
    Ok(blocks)
}

/// The fields of a texture record, in file order.
const TEXTURE_FIELDS: [&str; 16] = [
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
];

fn parse_texture(c: &mut Cursor, first_expected: u64) -> Result<TextureInfo> {
    let mut f = [0u32; 16];
    for (v, name) in f.iter_mut().zip(TEXTURE_FIELDS) {
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
    let layout = LeafLayout {
        width,
        height,
        faces,
        mips,
        channels,
    };
    check_layout(&layout)?;
    check_grid(n0, n1, s0, s1)?;
    let t = TextureInfo {
        id: TextureId { object, layer },
        grid: ParamGrid { n0, n1 },
        layout,
        stagger: [s0, s1],
        blocks: [b0, b1],
        first_block: first,
        screen_area: f32::from_bits(area),
    };
    check_placement(&t, first_expected)?;
    Ok(t)
}

fn in_range(field: &'static str, v: u32, lo: u32, hi: u32) -> Result<()> {
    if v < lo || v > hi {
        Err(bad(field, v as u64, format!("{lo}..={hi}")))
    } else {
        Ok(())
    }
}

/// Size, faces, MIP count and channels of a texture record.
fn check_layout(l: &LeafLayout) -> Result<()> {
    in_range("width", l.width, 1, MAX_DIM)?;
    in_range("height", l.height, 1, MAX_DIM)?;
    if l.faces != 1 && l.faces != 6 {
        return Err(bad("faces", l.faces as u64, "1 or 6"));
    }
    in_range("mips", l.mips, 1, LeafLayout::max_mips(l.width, l.height))?;
    in_range("channels", l.channels, 3, 4)
}

/// Parameter grid and block staggering of a texture record.
fn check_grid(n0: u32, n1: u32, s0: u32, s1: u32) -> Result<()> {
    in_range("n0", n0, 1, MAX_SAMPLES_PER_DIM)?;
    in_range("n1", n1, 1, MAX_SAMPLES_PER_DIM)?;
    if n0 as u64 * n1 as u64 > MAX_SAMPLES {
        return Err(bad(
            "n0*n1",
            n0 as u64 * n1 as u64,
            format!("at most {MAX_SAMPLES}"),
        ));
    }
    let bsz = 1u32 << BLOCK_LOG2;
    in_range("stagger0", s0, 0, bsz - 1)?;
    in_range("stagger1", s1, 0, if n1 > 1 { bsz - 1 } else { 0 })
}

/// Block counts, first block and screen area of a parsed texture.
fn check_placement(t: &TextureInfo, first_expected: u64) -> Result<()> {
    let lb = t.log2b();
    let ([n0, n1], [s0, s1], [b0, b1]) = ([t.grid.n0, t.grid.n1], t.stagger, t.blocks);
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
    if t.first_block as u64 != first_expected {
        return Err(bad(
            "first_block",
            t.first_block as u64,
            first_expected.to_string(),
        ));
    }
    if !(t.screen_area.is_finite() && t.screen_area >= 0.0) {
        let area = t.screen_area.to_bits();
        return Err(bad("screen_area", area as u64, "finite and non-negative"));
    }
    Ok(())
}
