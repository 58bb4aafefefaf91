//! The container reader's messages: each names the file once, the OS's
//! reason once.

use super::Container;
use crate::error::CodecError;

/// `e` with its `source()` chain, the way anyhow's `{:#}` prints it.
fn chain(e: &CodecError) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        text += &format!(": {s}");
        source = s.source();
    }
    text
}

#[test]
fn a_missing_file_is_named_once_with_the_os_reason_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("nosuch.ptxc");
    let e = Container::open(&path).expect_err("no such file");
    let text = chain(&e);
    let reason = match std::fs::File::open(&path) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("{} exists", path.display()),
    };
    assert_eq!(text.matches("nosuch.ptxc").count(), 1, "{text}");
    assert_eq!(text.matches(&reason).count(), 1, "{text}");
    assert!(text == format!("{}: {reason}", path.display()), "{text}");
    assert!(matches!(e, CodecError::Io { .. }), "{e:?}");
}

#[test]
fn a_bad_file_is_named_once_and_its_error_kept() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("bad.ptxc");
    std::fs::write(&path, b"XXXX and then some more bytes than a fixed header").expect("write");
    let e = Container::open(&path).expect_err("not a container");
    let text = chain(&e);
    assert_eq!(text.matches("bad.ptxc").count(), 1, "{text}");
    assert!(
        text.starts_with(&format!("{}: not a codec container", path.display())),
        "{text}"
    );
    assert!(matches!(e.inner(), CodecError::BadMagic { .. }), "{e:?}");
    // In memory there is no file to name.
    let e = Container::from_bytes(b"XXXX".repeat(8)).expect_err("not a container");
    assert!(matches!(e, CodecError::BadMagic { .. }), "{e:?}");
}

/// A container of 3 textures over 200 samples: a header over 1,000 bytes,
/// blocks after it back to back.
fn sample_file() -> Vec<u8> {
    use crate::input::ParamGrid;
    use crate::synth::{SynthSpec, scene};
    let mut spec = SynthSpec::cube(3, 1, ParamGrid::one_d(200), 8);
    spec.faces = 1;
    let input = scene(&spec);
    let target = crate::Target::Ratio(8.0);
    let (bytes, _) =
        crate::encode(&input, target, &crate::EncodeOptions::default()).expect("encode");
    bytes
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// `bytes` written to `name` in `dir`, then opened: the error.
fn open_err(dir: &std::path::Path, name: &str, bytes: &[u8]) -> (String, CodecError) {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    let e = Container::open(&path).expect_err("opened");
    (path.display().to_string(), e)
}

#[test]
fn counts_are_written_with_thousands_separators() {
    use crate::error::Grouped;
    let cases = [
        (0, "0"),
        (20, "20"),
        (999, "999"),
        (1_000, "1,000"),
        (1_328, "1,328"),
        (3_538_709, "3,538,709"),
        (u64::MAX, "18,446,744,073,709,551,615"),
    ];
    for (n, text) in cases {
        assert_eq!(Grouped(n).to_string(), text);
    }
}

#[test]
fn a_file_cut_in_its_header_says_how_long_the_header_is() {
    let f = sample_file();
    let h = u32_at(&f, 8) as usize;
    assert!(
        h > 1_000,
        "header of {h} bytes: too small to show a separator"
    );
    let dir = tempfile::tempdir().expect("tempdir");
    for len in [12, 20, 1_000.min(h - 1), h - 1] {
        let (path, e) = open_err(dir.path(), "trunc.ptxc", &f[..len]);
        let want = format!(
            "{path}: truncated: {} bytes, but its header alone is {} bytes",
            crate::error::Grouped(len as u64),
            crate::error::Grouped(h as u64)
        );
        assert_eq!(e.to_string(), want);
        // The same from memory, without the path.
        let e = Container::from_bytes(f[..len].to_vec()).expect_err("cut");
        assert_eq!(format!("{path}: {e}"), want);
    }
    for len in [0, 3, 7, 11] {
        let e = Container::from_bytes(f[..len].to_vec()).expect_err("cut");
        assert_eq!(
            e.to_string(),
            format!("truncated: {len} bytes, but a container's header alone is at least 32 bytes")
        );
    }
}

#[test]
fn a_file_cut_in_its_blocks_names_the_block_that_ends_last() {
    let f = sample_file();
    let nb = u32_at(&f, 16) as usize;
    let dir = tempfile::tempdir().expect("tempdir");
    let half = f.len() / 2;
    let (path, e) = open_err(dir.path(), "trunchalf.ptxc", &f[..half]);
    assert_eq!(
        e.to_string(),
        format!(
            "{path}: truncated: {} bytes, but block {} ends at byte {}",
            crate::error::Grouped(half as u64),
            nb - 1,
            crate::error::Grouped(f.len() as u64)
        )
    );
    assert!(f.len() >= 1_000, "{} bytes", f.len());
}

#[test]
fn a_corrupt_header_len_is_not_called_truncation() {
    let f = sample_file();
    let h = u32_at(&f, 8);
    let (nt, nb) = (u32_at(&f, 12), u32_at(&f, 16));
    let with_len = |bytes: &[u8], v: u32| {
        let mut g = bytes.to_vec();
        g[8..12].copy_from_slice(&v.to_le_bytes());
        Container::from_bytes(g)
            .expect_err("corrupt header_len")
            .to_string()
    };
    // Longer or shorter than the counts say, whole file or cut.
    for (bytes, v) in [(&f[..], h + 16), (&f[..], u32::MAX), (&f[..20], u32::MAX)] {
        let e = with_len(bytes, v);
        assert_eq!(
            e,
            format!(
                "container header: field header_len = {v}, expected {h} for {nt} textures and {nb} blocks"
            )
        );
    }
    // Below the smallest header.
    for v in [0, 8, 31] {
        let e = with_len(&f, v);
        assert_eq!(
            e,
            format!("container header: field header_len = {v}, expected at least 32")
        );
    }
}
