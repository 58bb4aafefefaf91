//! Hostile containers: every case must give a clear error, never a panic,
//! an out-of-bounds access or an allocation the file does not justify.

use codec::container::{FIXED_HEADER, TEX_RECORD};
use codec::error::Implied;
use codec::synth::{SynthSpec, scene};
use codec::{CodecError, Container, DecodeCache, EncodeOptions, ParamGrid, Target, encode};
use proptest::prelude::*;

fn sample_file() -> Vec<u8> {
    let mut spec = SynthSpec::cube(2, 1, ParamGrid::one_d(10), 8);
    spec.faces = 1;
    let input = scene(&spec);
    encode(&input, Target::Ratio(8.0), &EncodeOptions::default())
        .unwrap()
        .0
}

fn header_len(b: &[u8]) -> usize {
    u32::from_le_bytes(b[8..12].try_into().unwrap()) as usize
}

/// Re-seals the header checksum after an edit, so the edit itself is tested.
fn reseal(b: &mut [u8]) {
    let h = header_len(b);
    let crc = crc32fast::hash(&b[..h - 4]);
    b[h - 4..h].copy_from_slice(&crc.to_le_bytes());
}

fn set_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// Opens and decodes everything, walking each texture's samples in order
/// and warming ahead after each; returns the first error.
fn open_and_decode(bytes: Vec<u8>) -> Result<(), CodecError> {
    let c = Container::from_bytes(bytes)?;
    let mut cache = DecodeCache::default();
    let mut first_err = None;
    for t in c.textures().to_vec() {
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s in 0..t.grid.n0 {
            if let Err(e) = cache.decode_leaf_all(&c, t.id.object, t.id.layer, [s, 0], &mut out) {
                first_err.get_or_insert(e);
            }
            // A steady walk: decoding ahead reads the next block too.
            if let Err(e) = cache.warm_ahead(&c, t.id.object, t.id.layer) {
                first_err.get_or_insert(e);
            }
        }
    }
    first_err.map_or(Ok(()), Err)
}

#[test]
fn intact_file_decodes() {
    open_and_decode(sample_file()).unwrap();
}

#[test]
fn every_truncation_is_an_error() {
    let f = sample_file();
    let h = header_len(&f);
    let nb = u32::from_le_bytes(f[16..20].try_into().unwrap()) as usize;
    for len in 0..f.len() {
        let r = open_and_decode(f[..len].to_vec());
        let e = r.expect_err("truncated file accepted");
        // Too short to read header_len; then its header; then its blocks.
        let implied = match len {
            0..12 => Implied::MinimumHeader,
            _ if len < h => Implied::Header(h as u64),
            _ => Implied::Block {
                block: nb - 1,
                end: f.len() as u64,
            },
        };
        assert!(
            matches!(e, CodecError::TruncatedFile { len: l, implied: i } if l == len as u64 && i == implied),
            "len {len}: {e}"
        );
    }
}

#[test]
fn every_single_bit_flip_is_caught_or_harmless() {
    let f = sample_file();
    for i in 0..f.len() {
        for bit in [0, 3, 7] {
            let mut g = f.clone();
            g[i] ^= 1 << bit;
            // Header and block checksums cover every byte, so any flip is an error.
            assert!(
                open_and_decode(g).is_err(),
                "flip at byte {i} bit {bit} went unnoticed"
            );
        }
    }
}

#[test]
fn wrong_version_is_named() {
    let mut f = sample_file();
    set_u32(&mut f, 4, 2);
    let e = Container::from_bytes(f).unwrap_err();
    assert!(
        matches!(
            e,
            CodecError::VersionMismatch {
                got: 2,
                expected: 1
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("version 2"));
    let mut f = sample_file();
    f[0] = b'X';
    assert!(matches!(
        Container::from_bytes(f),
        Err(CodecError::BadMagic { .. })
    ));
}

#[test]
fn block_offsets_past_the_end_are_rejected() {
    let f = sample_file();
    let nt = u32::from_le_bytes(f[12..16].try_into().unwrap()) as usize;
    let index = FIXED_HEADER + TEX_RECORD * nt;
    // (field offset in the entry, value, whether it reads as a cut file)
    for (field_off, value, cut) in [
        (0usize, f.len() as u64 - 3, true),
        (0, u64::MAX - 2, false),
        (0, 0, false),
        (8, u32::MAX as u64, true),
    ] {
        let mut g = f.clone();
        let at = index + 16 + field_off; // second block entry
        if field_off == 0 {
            g[at..at + 8].copy_from_slice(&value.to_le_bytes());
        } else {
            set_u32(&mut g, at, value as u32);
        }
        reseal(&mut g);
        let e = Container::from_bytes(g).unwrap_err();
        // Past this file's end: cut; over the header or past any end: corrupt.
        if cut {
            assert!(
                matches!(
                    e,
                    CodecError::TruncatedFile {
                        implied: Implied::Block { block: 1, .. },
                        ..
                    }
                ),
                "{e}"
            );
        } else {
            assert!(
                matches!(e, CodecError::BlockOutOfRange { block: 1, .. }),
                "{e}"
            );
        }
    }
}

#[test]
fn huge_declared_sizes_are_rejected_before_allocating() {
    let f = sample_file();
    let tex = FIXED_HEADER;
    // (field offset in the texture record, value)
    let cases = [
        (8, 8192u32),   // width: would declare far more than the file justifies
        (8, 100_000),   // width over the limit
        (16, 7),        // faces
        (20, 99),       // mips
        (24, 9),        // channels
        (28, u32::MAX), // n0
        (40, 9),        // stagger0 ≥ block size
        (44, 1000),     // blocks0 inconsistent
    ];
    for (off, v) in cases {
        let mut g = f.clone();
        set_u32(&mut g, tex + off, v);
        if off == 8 {
            set_u32(&mut g, tex + 12, v); // height too
        }
        reseal(&mut g);
        let e = Container::from_bytes(g).unwrap_err();
        assert!(
            matches!(
                e,
                CodecError::ImplausibleSize { .. } | CodecError::BadField { .. }
            ),
            "field at {off} = {v}: {e}"
        );
    }
    // A header claiming billions of textures/blocks is a length mismatch, not an allocation.
    let mut g = f.clone();
    set_u32(&mut g, 12, u32::MAX);
    reseal_guarded(&mut g);
    assert!(Container::from_bytes(g).is_err());
    let mut g = f;
    set_u32(&mut g, 8, u32::MAX);
    assert!(matches!(
        Container::from_bytes(g),
        Err(CodecError::BadField {
            field: "header_len",
            ..
        })
    ));
}

fn reseal_guarded(b: &mut [u8]) {
    if header_len(b) <= b.len() {
        reseal(b);
    }
}

#[test]
fn corrupt_block_internals_with_valid_checksums_are_errors() {
    // Rewrite a block's bytes and its checksum, so the structural checks run.
    let f = sample_file();
    let c = Container::from_bytes(f.clone()).unwrap();
    let e0 = c.block_entries()[0];
    let nt = c.textures().len();
    let entry_crc_at = FIXED_HEADER + TEX_RECORD * nt + 12;
    let start = e0.offset as usize;
    let mut seen_error = 0;
    for i in 0..e0.len as usize {
        for x in [0x01u8, 0x80, 0xff] {
            let mut g = f.clone();
            g[start + i] ^= x;
            let crc = crc32fast::hash(&g[start..start + e0.len as usize]);
            set_u32(&mut g, entry_crc_at, crc);
            reseal(&mut g);
            // Must not panic; may decode (a changed coefficient) or error.
            if open_and_decode(g).is_err() {
                seen_error += 1;
            }
        }
    }
    assert!(seen_error > 0, "no structural corruption was detected");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = open_and_decode(bytes);
    }

    #[test]
    fn random_edits_never_panic(edits in proptest::collection::vec((any::<u16>(), any::<u8>()), 1..6), fix in any::<bool>()) {
        let mut f = sample_file_cached().clone();
        for (at, v) in edits {
            let i = at as usize % f.len();
            f[i] = v;
        }
        if fix && header_len(&f) <= f.len() && header_len(&f) >= 8 {
            reseal(&mut f);
        }
        let _ = open_and_decode(f);
    }
}

fn sample_file_cached() -> &'static Vec<u8> {
    static F: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    F.get_or_init(sample_file)
}
