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
