//! The compiled scene shipped with the engine (`assets/compiled/<scene>/`):
//! the container and the room's light maps the engine itself produced,
//! each with the key record of the inputs it was compiled from. The main
//! job plays them, read only, when their keys match what it would compile
//! now (scene file, tracer, solve and codec versions, frame size), so a
//! fresh clone shows its first frame without the 40-minute compile; any
//! difference in inputs makes them stale and the pipeline runs as before.
//! `engine compile --scene teapot --ship assets/compiled/teapot`
//! regenerates them (`--scene glass … assets/compiled/glass`: the glass
//! object's per-sample shell maps and the room's light maps); a test fails
//! when their keys no longer match.

use super::CompileContext;
use anyhow::{Context, Result, bail};
use inference::key::{Freshness, freshness, record_path};
use inference::scene::Scene;
use std::path::{Path, PathBuf};

/// Where the engine's shipped compiled scenes live in the source tree.
pub fn root() -> PathBuf {
    let engine = Path::new(env!("CARGO_MANIFEST_DIR"));
    engine
        .parent()
        .unwrap_or(engine)
        .join("assets")
        .join("compiled")
}

/// `assets/compiled/<scene>` when the engine ships data for `scene`.
pub fn dir(scene: &Scene) -> Option<PathBuf> {
    let d = root().join(&scene.name);
    d.is_dir().then_some(d)
}

/// The shipped files under `dir` (container, room light maps and their
/// layouts, a glass object's per-sample shell maps), as paths relative to
/// `dir`, in a stable order.
pub fn files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for sub in ["", "room", "glass"].map(PathBuf::from) {
        let Ok(entries) = std::fs::read_dir(dir.join(&sub)) else {
            continue;
        };
        for e in entries {
            let e = e.with_context(|| format!("reading {}", dir.join(&sub).display()))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let shipped = name.ends_with(".ptxc")
                || name.ends_with(".light.exr")
                || name.ends_with(".light.json");
            if shipped {
                found.push(sub.join(name));
            }
        }
    }
    found.sort();
    Ok(found)
}

/// Copies the compiled containers and room light maps of `ctx` (fresh
/// under its output folder) with their key records into `dest`, replacing
/// only files the engine shipped before.
pub fn ship(ctx: &CompileContext, dest: &Path) -> Result<Vec<PathBuf>> {
    let files = files(ctx.out)?;
    if !files.iter().any(|f| is_container(f)) {
        bail!("{}: no compiled container to ship", ctx.out.display());
    }
    copy_with_records(ctx.out, dest, &files)
}

fn is_container(rel: &Path) -> bool {
    rel.extension().is_some_and(|e| e == "ptxc")
}

/// Copies each of `files` (relative paths) from `from` into `dest` with its
/// key record. A file already at the destination is replaced only when it is
/// the engine's (a record of this engine beside it); the record is written
/// last, so an interrupted copy reads as damaged, never as fresh.
fn copy_with_records(from: &Path, dest: &Path, files: &[PathBuf]) -> Result<Vec<PathBuf>> {
    crate::util::files::claim_dir(dest)?;
    let mut written = Vec::new();
    for rel in files {
        let (src, to) = (from.join(rel), dest.join(rel));
        if let Some(parent) = to.parent() {
            crate::util::files::claim_dir(parent)?;
        }
        crate::util::files::check_overwrite_keyed(&to)?;
        for (src, to) in [
            (src.clone(), to.clone()),
            (record_path(&src), record_path(&to)),
        ] {
            let bytes =
                std::fs::read(&src).with_context(|| format!("reading {}", src.display()))?;
            crate::util::files::write(&to, &bytes)?;
        }
        written.push(to);
    }
    Ok(written)
}

/// The shipped container of `ctx`'s scene when its key is `key`; says why
/// it is passed over otherwise (a stale shipped file is not an error: the
/// pipeline compiles instead).
pub fn container(ctx: &CompileContext, key: &inference::key::Key) -> Option<PathBuf> {
    let dir = ctx.shipped.as_ref()?;
    let path = dir.join(format!("{}.ptxc", ctx.scene.name));
    match freshness(&path, key) {
        Freshness::Fresh => Some(path),
        Freshness::Missing => None,
        why => {
            eprintln!(
                "{}: not played ({}); compiling instead",
                path.display(),
                super::room::describe(&why)
            );
            None
        }
    }
}

/// Each shipped file of `ctx.shipped` (as `ctx.out`) with whether it
/// matches the key it would be compiled with today ("fresh", or what
/// changed); fails when there is no container.
pub fn check(ctx: &CompileContext) -> Result<Vec<(String, String)>> {
    let files = files(ctx.out)?;
    if !files.iter().any(|f| is_container(f)) {
        bail!("{}: no shipped container", ctx.out.display());
    }
    // Each kind's key only when a file of that kind is shipped.
    let any = |top: &str| files.iter().any(|f| f.starts_with(top));
    let room = any("room")
        .then(|| super::room::expected_key(ctx))
        .transpose()?;
    let glass = match any("glass") {
        true => Some(
            super::glass_shells::expected_key(ctx.scene, ctx.size)
                .context("glass/ is shipped but the scene asks for no per-sample shell maps")?,
        ),
        false => None,
    };
    let top = files.iter().any(|f| f.components().count() == 1);
    let container = top.then(|| super::container_key_for(ctx)).transpose()?;
    Ok(files
        .iter()
        .map(|rel| {
            let key = match () {
                _ if rel.starts_with("room") => room.as_ref(),
                _ if rel.starts_with("glass") => glass.as_ref(),
                _ => container.as_ref(),
            };
            let path = ctx.out.join(rel);
            let fresh = key.map_or(Freshness::Missing, |key| freshness(&path, key));
            (path.display().to_string(), super::room::describe(&fresh))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use inference::key::{Key, write_record};

    fn compiled(dir: &Path, rel: &str, bytes: &[u8]) {
        let path = dir.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, bytes).unwrap();
        write_record(&path, &Key::new().with("test", bytes.len() as u64)).unwrap();
    }

    #[test]
    fn a_shipped_set_is_replaced_by_a_newer_one() {
        let (out, dest) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let files = [
            PathBuf::from("s.ptxc"),
            PathBuf::from("room/floor.light.exr"),
        ];
        compiled(out.path(), "s.ptxc", b"first");
        compiled(out.path(), "room/floor.light.exr", b"light");
        copy_with_records(out.path(), dest.path(), &files).unwrap();
        compiled(out.path(), "s.ptxc", b"second, longer");
        copy_with_records(out.path(), dest.path(), &files).unwrap();
        let shipped = dest.path().join("s.ptxc");
        assert_eq!(std::fs::read(&shipped).unwrap(), b"second, longer");
        assert!(
            inference::key::is_ours(&shipped),
            "record matches the new bytes"
        );
    }

    #[test]
    fn a_file_or_record_the_engine_did_not_write_is_not_overwritten() {
        let (out, dest) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let files = [PathBuf::from("s.ptxc")];
        compiled(out.path(), "s.ptxc", b"compiled");
        copy_with_records(out.path(), dest.path(), &files).unwrap();
        std::fs::remove_file(dest.path().join("s.ptxc")).unwrap();
        std::fs::write(dest.path().join("s.ptxc.key"), b"a user's notes").unwrap();
        let e = copy_with_records(out.path(), dest.path(), &files).unwrap_err();
        assert!(e.to_string().contains("s.ptxc.key"), "{e}");
        assert_eq!(
            std::fs::read(dest.path().join("s.ptxc.key")).unwrap(),
            b"a user's notes"
        );
        std::fs::remove_file(dest.path().join("s.ptxc.key")).unwrap();
        std::fs::write(dest.path().join("s.ptxc"), b"a user's file").unwrap();
        let e = copy_with_records(out.path(), dest.path(), &files).unwrap_err();
        assert!(e.to_string().contains("not overwritten"), "{e}");
        assert_eq!(
            std::fs::read(dest.path().join("s.ptxc")).unwrap(),
            b"a user's file"
        );
    }
}
