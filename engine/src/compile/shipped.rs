//! The compiled scene shipped with the engine (`assets/compiled/<scene>/`):
//! the container and the room's light maps the engine itself produced,
//! each with the key record of the inputs it was compiled from. The main
//! job plays them, read only, when their keys match what it would compile
//! now (scene file, tracer, solve and codec versions, frame size), so a
//! fresh clone shows its first frame without the 40-minute compile; any
//! difference in inputs makes them stale and the pipeline runs as before.
//! `engine compile --scene teapot --ship assets/compiled/teapot`
//! regenerates them; a test fails when their keys no longer match.

use super::CompileContext;
use crate::maps::DataDirs;
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
/// layouts), as paths relative to `dir`, in a stable order.
pub fn files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for sub in [PathBuf::new(), PathBuf::from("room")] {
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

/// Copies the compiled container and room light maps of `ctx` (fresh under
/// its output folder) with their key records into `dest`, replacing only
/// files the engine shipped before.
pub fn ship(ctx: &CompileContext, dest: &Path) -> Result<Vec<PathBuf>> {
    let container = DataDirs::under(ctx.out, ctx.scene).container;
    if !container.is_file() {
        bail!("{}: no compiled container to ship", container.display());
    }
    crate::util::files::claim_dir(dest)?;
    let mut written = Vec::new();
    for rel in files(ctx.out)? {
        let (from, to) = (ctx.out.join(&rel), dest.join(&rel));
        if let Some(parent) = to.parent() {
            crate::util::files::claim_dir(parent)?;
        }
        for (from, to) in [
            (from.clone(), to.clone()),
            (record_path(&from), record_path(&to)),
        ] {
            crate::util::files::check_overwrite_keyed(&to)?;
            let bytes =
                std::fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
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
    let dir = ctx.out;
    let container = super::container_key_for(ctx)?;
    let room = super::room::expected_key(ctx)?;
    let files = files(dir)?;
    if !files
        .iter()
        .any(|f| f.extension().is_some_and(|e| e == "ptxc"))
    {
        bail!("{}: no shipped container", dir.display());
    }
    Ok(files
        .iter()
        .map(|rel| {
            let key = if rel.starts_with("room") {
                &room
            } else {
                &container
            };
            let path = dir.join(rel);
            (
                path.display().to_string(),
                super::room::describe(&freshness(&path, key)),
            )
        })
        .collect())
}
