//! Where the engine may write, and how. It writes only into folders it
//! made (marked by a [`MARKER`] file) or that were empty when it first
//! wrote there, and into single files that are absent or its own (a key
//! record beside them, see `inference::key`). Every write is atomic under a
//! unique temporary name, so a crash or a second process never leaves or
//! reads half a file.

use anyhow::{Context, Result, bail};
use std::path::Path;

/// The file that marks a folder as the engine's own.
pub const MARKER: &str = ".pem-engine";

/// Makes `dir` the engine's to write into: creates it (with its parents)
/// when missing, accepts it when marked or empty, refuses anything else,
/// and proves it writable, all before any work starts.
pub fn claim_dir(dir: &Path) -> Result<()> {
    let marker = dir.join(MARKER);
    if marker.is_file() {
        return Ok(());
    }
    if dir.exists() && !dir.is_dir() {
        bail!(
            "{}: a file, expected an output folder (a new, empty or engine-made one)",
            dir.display()
        );
    }
    if dir.exists() {
        let mut entries = std::fs::read_dir(dir)
            .with_context(|| format!("output folder {} cannot be read", dir.display()))?;
        if entries.next().is_some() {
            bail!(
                "{}: a folder the engine did not make (no {MARKER} file) and not empty: \
                 the engine writes only into folders it made; choose a new or empty folder",
                dir.display()
            );
        }
    } else {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    }
    std::fs::write(
        &marker,
        "made by pem-engine: it may overwrite its own files here\n",
    )
    .with_context(|| format!("output folder {} is not writable", dir.display()))
}

/// Whether `path` may be written: absent, inside a folder the engine made,
/// or recorded as the engine's own. Checked before work that ends in
/// writing it.
pub fn check_overwrite(path: &Path) -> Result<()> {
    if !path.exists() {
        return Ok(());
    }
    if path.is_dir() {
        bail!("{}: is a folder, expected a file", path.display());
    }
    let in_our_dir = path.parent().is_some_and(|d| d.join(MARKER).is_file());
    if in_our_dir || inference::key::is_ours(path) {
        return Ok(());
    }
    bail!(
        "{}: exists and is not a file the engine wrote (no key record beside it): not overwritten; \
         move it away or choose another path",
        path.display()
    )
}

/// [`check_overwrite`], and the folder `path` goes in exists: a command
/// that writes one named file at the end of long work fails before it.
pub fn check_output_file(path: &Path) -> Result<()> {
    check_overwrite(path)?;
    check_folder_exists(path)
}

/// The folder the file `path` goes in exists (a command that writes one
/// named file at the end of long work checks it before).
pub fn check_folder_exists(path: &Path) -> Result<()> {
    let folder = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !folder.is_dir() {
        bail!(
            "{}: the folder {} does not exist (expected an existing folder: create it first)",
            path.display(),
            folder.display()
        );
    }
    Ok(())
}

/// Whether a keyed output (a container, a map) and its key record may be
/// written at `path`: absent, or carrying a key record this engine wrote
/// (stale or damaged files of its own are rebuilt; anything else is
/// refused, wherever it is, a foreign file at the record's path included).
pub fn check_overwrite_keyed(path: &Path) -> Result<()> {
    let record = inference::key::record_path(path);
    if inference::key::read_record(path).is_some() || !record.exists() && !path.exists() {
        return Ok(());
    }
    if !path.exists() {
        bail!(
            "{}: exists and is not a key record this engine wrote: not overwritten; move it away",
            record.display()
        );
    }
    bail!(
        "{}: exists and is not a file the engine compiled (no key record beside it): not overwritten; \
         move it away or choose another path",
        path.display()
    )
}

/// Writes `bytes` to `path` atomically (unique temporary, then rename).
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    Ok(inference::files::write_bytes(path, bytes)?)
}

/// Runs `write` on a unique temporary path beside `path`, then renames it
/// onto `path`; the temporary is removed when anything fails. For files
/// another library or program writes by name.
pub fn write_through(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = inference::files::temp_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        anyhow::anyhow!("{}: {e}", path.display())
    })
}

/// Writes `value` as pretty JSON to `path` atomically.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let json = serde_json::to_vec_pretty(value)
        .with_context(|| format!("serialising {}", path.display()))?;
    write(path, &json)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn claims_new_empty_and_marked_folders_only() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let new = dir.path().join("a/b");
        claim_dir(&new)?;
        assert!(new.join(MARKER).is_file());
        std::fs::write(new.join("frame_0000.png"), b"x")?;
        claim_dir(&new)?; // marked: ours, files and all
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty)?;
        claim_dir(&empty)?;
        let foreign = dir.path().join("foreign");
        std::fs::create_dir(&foreign)?;
        std::fs::write(foreign.join("thesis.tex"), b"mine")?;
        let e = claim_dir(&foreign).expect_err("not ours").to_string();
        assert!(e.contains("foreign") && e.contains(MARKER), "{e}");
        assert!(!foreign.join(MARKER).exists());
        let file = dir.path().join("notes.txt");
        std::fs::write(&file, b"mine")?;
        let e = claim_dir(&file).expect_err("a file").to_string();
        assert!(
            e.contains("notes.txt: a file, expected an output folder"),
            "{e}"
        );
        assert_eq!(std::fs::read(&file)?, b"mine");
        Ok(())
    }

    #[test]
    fn keyed_outputs_need_their_record_even_in_our_folders() -> Result<()> {
        let dir = tempfile::tempdir()?;
        claim_dir(dir.path())?;
        let file = dir.path().join("teapot.ptxc");
        check_overwrite_keyed(&file)?;
        std::fs::write(&file, b"notes")?;
        assert!(check_overwrite_keyed(&file).is_err());
        inference::key::write_record(&file, &inference::key::Key::new())?;
        std::fs::write(&file, b"damaged since")?;
        check_overwrite_keyed(&file)?; // ours, damaged: rebuilt
        let lone = dir.path().join("other.ptxc");
        std::fs::write(inference::key::record_path(&lone), b"a user's notes")?;
        let e = check_overwrite_keyed(&lone)
            .expect_err("not our record")
            .to_string();
        assert!(e.contains("other.ptxc.key"), "{e}");
        Ok(())
    }

    #[test]
    fn overwrites_only_absent_or_own_files() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let file = dir.path().join("scene.ptxc");
        check_overwrite(&file)?;
        std::fs::write(&file, b"someone's notes")?;
        let e = check_overwrite(&file).expect_err("foreign").to_string();
        assert!(
            e.contains("scene.ptxc") && e.contains("not overwritten"),
            "{e}"
        );
        inference::key::write_record(&file, &inference::key::Key::new().with("x", 1))?;
        check_overwrite(&file)?;
        let owned = dir.path().join("owned");
        claim_dir(&owned)?;
        std::fs::write(owned.join("perf.json"), b"{}")?;
        check_overwrite(&owned.join("perf.json"))?;
        Ok(())
    }
}
