//! Whole-file writes that never leave half a file behind and never collide:
//! every write goes to a temporary name unique to this process and call, in
//! the target's folder (so the final rename is atomic), and the temporary
//! is removed when anything fails.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// How every EXR the engine writes is encoded: run-length, as `exr`'s
/// `FAST_LOSSLESS`, but with its blocks in increasing order. Unspecified
/// order lets the parallel compressor write them as they finish, so the
/// same pixels made different bytes from run to run (and different
/// checksums in the key records of files a farmed compile should share).
pub const EXR_ENCODING: exr::prelude::Encoding = exr::prelude::Encoding {
    line_order: exr::prelude::LineOrder::Increasing,
    ..exr::prelude::Encoding::FAST_LOSSLESS
};

/// Samples (pixels × channels, over every part) an EXR read back may
/// declare: more than any file the engine writes (an 8192 × 8192 frame
/// with 32 channels). The decoder sizes its buffers from the header, so a
/// damaged or foreign header declaring more is refused with its size (the
/// `exr` crate refuses the test's damaged file by its chunk count too;
/// this check does not depend on that).
const MAX_EXR_SAMPLES: u64 = 8192 * 8192 * 32;

/// Why an EXR's header is not read further.
pub enum ExrHeader {
    Unreadable(exr::error::Error),
    /// What it declares, for the message.
    TooLarge(String),
}

/// The EXR `bytes` declare at most [`MAX_EXR_SAMPLES`].
pub fn check_exr_size(bytes: &[u8]) -> Result<(), ExrHeader> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(ExrHeader::Unreadable)?;
    let mut samples = 0u64;
    for header in &meta.headers {
        let exr::math::Vec2(w, h) = header.layer_size;
        let channels = header.channels.list.len();
        let part = (w as u64)
            .checked_mul(h as u64)
            .and_then(|n| n.checked_mul(channels as u64));
        samples = match part.and_then(|n| samples.checked_add(n)) {
            Some(n) if n <= MAX_EXR_SAMPLES => n,
            _ => {
                return Err(ExrHeader::TooLarge(format!(
                    "a part of {w}x{h} pixels × {channels} channels, {} parts: more than \
                     {MAX_EXR_SAMPLES} samples (an 8192x8192 frame with 32 channels)",
                    meta.headers.len()
                )));
            }
        };
    }
    Ok(())
}

/// `dir/.<name>.<pid>.<n>.tmp`: hidden, beside `path`, unique per process
/// and call, so concurrent writers of the same file never share one.
pub fn temp_path(path: &Path) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}

/// An atomic write that failed: in the caller's `write` or in the rename.
#[derive(Debug, thiserror::Error)]
pub enum AtomicError<E: std::error::Error + 'static> {
    #[error(transparent)]
    Write(E),
    #[error("{}: {source}", path.display())]
    Rename {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Runs `write` on a temporary path, then renames it onto `path`.
pub fn write_with<E: std::error::Error + 'static>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), AtomicError<E>> {
    let tmp = temp_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(AtomicError::Write(e));
    }
    std::fs::rename(&tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        AtomicError::Rename {
            path: path.to_owned(),
            source,
        }
    })
}

/// An I/O error naming the file it happened to.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct FileError {
    pub path: PathBuf,
    pub source: std::io::Error,
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_with(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|source| FileError {
            path: path.to_owned(),
            source,
        })
    })
    .map_err(|e| match e {
        AtomicError::Write(e) => e,
        AtomicError::Rename { path, source } => FileError { path, source },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporaries_are_unique_and_beside_the_target() {
        let p = Path::new("dir/frame.png");
        let (a, b) = (temp_path(p), temp_path(p));
        assert_ne!(a, b);
        assert_eq!(a.parent(), p.parent());
        assert!(
            a.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with(".frame.png."))
        );
    }

    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("a.json");
        write_bytes(&path, b"one").expect("first");
        write_bytes(&path, b"two").expect("second");
        assert_eq!(std::fs::read(&path).expect("read"), b"two");
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("ls").collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn a_failed_write_leaves_nothing_and_names_the_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("missing/a.json");
        let e = write_bytes(&path, b"x").expect_err("no folder");
        assert!(e.to_string().contains("a.json"), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).expect("ls").count(), 0);
    }

    #[test]
    fn concurrent_writers_of_one_file_all_succeed() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("perf.json");
        std::thread::scope(|s| {
            for i in 0..8 {
                let path = &path;
                s.spawn(move || write_bytes(path, format!("{i}").as_bytes()).expect("write"));
            }
        });
        assert!(
            std::fs::read_to_string(&path)
                .expect("read")
                .parse::<u32>()
                .is_ok()
        );
    }
}
