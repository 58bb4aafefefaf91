//! Content keys for caches: FNV-1a, 64-bit, stable across runs, platforms
//! and Rust releases (unlike `std`'s `DefaultHasher`), and keys made of
//! named parts, so a stale file can say *what* changed.

use glam::{Vec2, Vec3};
use std::hash::Hasher;

/// FNV-1a, 64-bit.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

impl Fnv {
    pub fn f32(&mut self, x: f32) {
        self.write_u32(x.to_bits());
    }
    pub fn v3(&mut self, v: Vec3) {
        v.to_array().into_iter().for_each(|x| self.f32(x));
    }
    pub fn v2(&mut self, v: Vec2) {
        v.to_array().into_iter().for_each(|x| self.f32(x));
    }
    /// A string with its length, so `("ab", "c")` and `("a", "bc")` differ.
    pub fn str(&mut self, s: &str) {
        self.write_u64(s.len() as u64);
        self.write(s.as_bytes());
    }
}

/// The key of one compiled file: named parts, each a hash of one input
/// (scene geometry, lights, settings, code version, …). Two keys are equal
/// when every part is; when they differ, [`Key::changes`] names the parts.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Key {
    pub parts: Vec<(String, String)>,
}

impl Key {
    pub fn new() -> Self {
        Self::default()
    }
    /// Adds the part `name` with hash `value` (replacing an earlier one).
    pub fn with(mut self, name: &str, value: u64) -> Self {
        let value = format!("{value:016x}");
        match self.parts.iter_mut().find(|(n, _)| n == name) {
            Some(part) => part.1 = value,
            None => self.parts.push((name.to_owned(), value)),
        }
        self
    }
    /// Every part of `other` added to this key.
    pub fn merged(self, other: &Key) -> Self {
        other.parts.iter().fold(self, |k, (n, v)| {
            let v = u64::from_str_radix(v, 16).unwrap_or(0);
            k.with(n, v)
        })
    }
    /// One number for all parts (for folding into other keys).
    pub fn hash(&self) -> u64 {
        let mut h = Fnv::default();
        for (n, v) in &self.parts {
            h.str(n);
            h.str(v);
        }
        h.finish()
    }
    /// The parts that differ between `self` (what the inputs are now) and
    /// `recorded`, e.g. `["lights", "spp"]`; parts only one side has count.
    pub fn changes(&self, recorded: &Key) -> Vec<String> {
        let mut changed: Vec<String> = self
            .parts
            .iter()
            .filter(|(n, v)| recorded.parts.iter().all(|(rn, rv)| rn != n || rv != v))
            .map(|(n, _)| n.clone())
            .collect();
        for (n, _) in &recorded.parts {
            if self.parts.iter().all(|(sn, _)| sn != n) {
                changed.push(n.clone());
            }
        }
        changed
    }
}

/// What a compiled file's key record says about it now.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Freshness {
    /// The file and its record exist, and the record's key is the key asked for.
    Fresh,
    /// No file, or no record of how it was made.
    Missing,
    /// Made from other inputs: the parts of the key that changed.
    Stale(Vec<String>),
    /// The file or its record is damaged (truncated, unreadable): why.
    Broken(String),
}

/// The record beside a compiled file: who wrote it, from which inputs, and
/// its size and checksum, so a truncated or altered file is never trusted.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Record {
    /// Always [`WRITER`]: the mark of a file this engine made.
    pub writer: String,
    pub key: Key,
    pub bytes: u64,
    pub crc32: u32,
    /// Seconds of work that made the file, counting the files it was made
    /// from where the writer says so (a compile's budget), when recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
}

/// The `writer` of every record this engine writes.
pub const WRITER: &str = "pem-engine";

/// `<file>.key`, the record beside `file`.
pub fn record_path(file: &std::path::Path) -> std::path::PathBuf {
    let mut s = file.as_os_str().to_owned();
    s.push(".key");
    std::path::PathBuf::from(s)
}

/// The record beside `file`, if there is a readable one this engine wrote.
pub fn read_record(file: &std::path::Path) -> Option<Record> {
    let text = std::fs::read(record_path(file)).ok()?;
    serde_json::from_slice::<Record>(&text)
        .ok()
        .filter(|r| r.writer == WRITER)
}

/// Whether `file` was made from inputs with `key` and is whole (its size
/// matches the record; the checksum is verified by [`read_verified`]).
pub fn freshness(file: &std::path::Path, key: &Key) -> Freshness {
    let Ok(meta) = std::fs::metadata(file) else {
        return Freshness::Missing;
    };
    let Some(record) = read_record(file) else {
        return if record_path(file).exists() {
            Freshness::Broken(format!(
                "{}: unreadable record",
                record_path(file).display()
            ))
        } else {
            Freshness::Missing
        };
    };
    if record.bytes != meta.len() {
        return Freshness::Broken(format!(
            "{}: {} bytes, its record says {}",
            file.display(),
            meta.len(),
            record.bytes
        ));
    }
    let changes = key.changes(&record.key);
    if changes.is_empty() {
        Freshness::Fresh
    } else {
        Freshness::Stale(changes)
    }
}

/// Whether `file` is this engine's (a record it wrote, matching the file's
/// size and checksum): only such files may be overwritten.
pub fn is_ours(file: &std::path::Path) -> bool {
    read_record(file).is_some() && read_verified(file).is_ok()
}

/// The bytes of `file`, checked against its record's size and checksum.
pub fn read_verified(file: &std::path::Path) -> Result<Vec<u8>, String> {
    let record = read_record(file)
        .ok_or_else(|| format!("{}: no record of how it was made", file.display()))?;
    let bytes = std::fs::read(file).map_err(|e| format!("{}: {e}", file.display()))?;
    if bytes.len() as u64 != record.bytes || crc32fast::hash(&bytes) != record.crc32 {
        return Err(format!(
            "{}: damaged ({} bytes, checksum {:08x}; its record says {} bytes, {:08x})",
            file.display(),
            bytes.len(),
            crc32fast::hash(&bytes),
            record.bytes,
            record.crc32
        ));
    }
    Ok(bytes)
}

/// Records that `file` (already in place) was made from inputs with `key`.
pub fn write_record(file: &std::path::Path, key: &Key) -> Result<(), crate::files::FileError> {
    write_record_timed(file, key, None)
}

/// [`write_record`], also recording the `seconds` of work `file` took.
pub fn write_record_timed(
    file: &std::path::Path,
    key: &Key,
    seconds: Option<f64>,
) -> Result<(), crate::files::FileError> {
    let io = |source| crate::files::FileError {
        path: file.to_owned(),
        source,
    };
    let bytes = std::fs::read(file).map_err(io)?;
    let record = Record {
        writer: WRITER.into(),
        key: key.clone(),
        bytes: bytes.len() as u64,
        crc32: crc32fast::hash(&bytes),
        seconds: seconds.filter(|s| s.is_finite() && *s >= 0.0),
    };
    let json = serde_json::to_vec_pretty(&record).map_err(|e| io(e.into()))?;
    crate::files::write_bytes(&record_path(file), &json)
}

/// The seconds of work recorded beside `file`, when its record has them.
pub fn recorded_seconds(file: &std::path::Path) -> Option<f64> {
    read_record(file)?.seconds
}

/// Removes `file` and its record (a damaged cache entry, to be rebuilt).
pub fn forget(file: &std::path::Path) {
    let _ = std::fs::remove_file(record_path(file));
    let _ = std::fs::remove_file(file);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv_matches_the_reference_vectors() {
        // FNV-1a 64 test vectors (Fowler, Noll, Vo).
        let h = |s: &[u8]| {
            let mut f = Fnv::default();
            f.write(s);
            f.finish()
        };
        assert_eq!(h(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(h(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(h(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn changes_name_the_parts_that_differ() {
        let now = Key::new()
            .with("lights", 1)
            .with("geometry", 2)
            .with("spp", 16);
        let old = Key::new()
            .with("lights", 9)
            .with("geometry", 2)
            .with("seed", 0);
        assert_eq!(now.changes(&old), ["lights", "spp", "seed"]);
        assert!(now.changes(&now).is_empty());
        assert_ne!(now.hash(), old.hash());
        assert_eq!(now.clone().merged(&Key::new()), now);
    }

    #[test]
    fn records_detect_stale_truncated_and_foreign_files() {
        let dir = tempfile::tempdir().expect("tempdir");
        let file = dir.path().join("map.exr");
        let key = Key::new().with("scene", 1);
        assert_eq!(freshness(&file, &key), Freshness::Missing);
        std::fs::write(&file, b"twelve bytes").expect("write");
        assert_eq!(freshness(&file, &key), Freshness::Missing, "no record");
        assert!(!is_ours(&file), "a file without a record is not ours");
        write_record(&file, &key).expect("record");
        assert_eq!(freshness(&file, &key), Freshness::Fresh);
        assert!(is_ours(&file));
        assert_eq!(
            freshness(&file, &Key::new().with("scene", 2)),
            Freshness::Stale(vec!["scene".into()])
        );
        std::fs::write(&file, b"twelve").expect("truncate");
        assert!(matches!(freshness(&file, &key), Freshness::Broken(_)));
        assert!(!is_ours(&file));
        std::fs::write(&file, b"twelve bytez").expect("alter");
        assert_eq!(freshness(&file, &key), Freshness::Fresh, "same size");
        assert!(read_verified(&file).is_err(), "checksum catches it");
        std::fs::write(record_path(&file), b"{not json").expect("garble");
        assert!(matches!(freshness(&file, &key), Freshness::Broken(_)));
        forget(&file);
        assert!(!file.exists() && !record_path(&file).exists());
    }
}
