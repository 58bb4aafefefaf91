//! `engine compile`: everything the main job plays for a scene, compiled
//! under the output folder without playing — whole, one shard of the
//! samples for a farmed compile, or the merge that finishes a farmed
//! compile (room light maps and the container from the shards' maps).

use super::shard::Shard;
use super::{CompileContext, map_source, missing_maps, room::room_maps, shipped};
use crate::options::{Mode, PemOptions, RunPlace};
use crate::util::files::claim_dir;
use anyhow::{Result, bail};
use inference::scene::Scene;
use std::fmt::Write;
use std::path::Path;

use std::time::Instant;

/// Which part of the compile this process does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Everything missing: traces, maps, room light maps, container.
    Whole,
    /// The traces and maps of one shard's samples only.
    Shard(Shard),
    /// Room light maps and container from maps every shard has finished;
    /// fails naming the samples still missing.
    Merge,
}

/// Compiles `part` of `place`'s scene under its output folder; with
/// `ship`, copies the compiled container and light maps there too.
pub fn compile_scene(place: &RunPlace, part: Part, ship: Option<&Path>) -> Result<String> {
    let scene = Scene::load(&place.scene)?;
    let out = place.out_dir(&scene);
    claim_dir(&out)?;
    let ctx = CompileContext {
        scene: &scene,
        scene_arg: &place.scene,
        out: &out,
        size: place.size,
        device: &place.device,
        shipped: None,
    };
    if Mode::default_for(&scene) == Mode::Hybrid {
        return compile_glass(&ctx, part, ship);
    }
    let start = Instant::now();
    let mut text = String::new();
    if let Part::Shard(shard) = part {
        let samples = shard.samples(scene.orbit.sample_count());
        text += &super::infer_samples(&ctx, &samples)?;
        writeln!(
            text,
            "shard {}/{}: {} samples compiled under {} in {:.1} s; when every shard is done, \
             `engine compile --scene {} --merge --out {}` finishes the compile",
            shard.index,
            shard.count,
            samples.len(),
            out.display(),
            start.elapsed().as_secs_f64(),
            place.scene,
            out.display()
        )?;
        return Ok(text);
    }
    if part == Part::Merge {
        let missing = missing_maps(&ctx)?;
        if !missing.is_empty() {
            bail!(
                "{}: {} samples have no fresh maps yet ({}): a shard is unfinished or its files \
                 were not copied here",
                out.display(),
                missing.len(),
                preview(&missing)
            );
        }
    }
    let room = room_maps(&ctx)?;
    // The container holds every layer of every sample whatever the layers
    // asked for (only a sphere EM would be read as EXR instead).
    map_source(&ctx, &PemOptions::default(), &[])?;
    writeln!(
        text,
        "{}: compiled under {} in {:.1} s ({} room light maps)",
        scene.name,
        out.display(),
        start.elapsed().as_secs_f64(),
        room.objects.len()
    )?;
    if let Some(dest) = ship {
        for file in shipped::ship(&ctx, dest)? {
            writeln!(text, "shipped {}", file.display())?;
        }
    }
    Ok(text)
}

/// `engine compile` of a glass scene: its per-sample shell maps' container
/// (what the first hybrid frame would otherwise solve for minutes) and the
/// room's light maps.
fn compile_glass(ctx: &CompileContext, part: Part, ship: Option<&Path>) -> Result<String> {
    if part != Part::Whole {
        bail!(
            "{}: a glass scene compiles in one part (no --shard or --merge)",
            ctx.scene.origin
        );
    }
    let layered = super::glass_shells::layered::LayeredObject::for_scene(ctx.scene, ctx.out)?;
    if let (Some(dest), Some(_)) = (ship, layered) {
        bail!(
            "--ship {}: {} has layered shells; their per-sample maps play from --out and are not shipped",
            dest.display(),
            ctx.scene.origin
        );
    }
    let start = Instant::now();
    let Some((file, bytes)) = super::glass_shells::compile(ctx)? else {
        bail!(
            "{}: nothing to compile: its glass object has no `shell_every` (per-sample shell \
             maps); its shell map is traced in seconds and its room's light maps compiled \
             when played (`engine --scene {}`)",
            ctx.scene.origin,
            ctx.scene_arg
        );
    };
    let mut text = format!(
        "{}: per-sample shell maps compiled under {} in {:.1} s: {} ({bytes} bytes)\n",
        ctx.scene.name,
        ctx.out.display(),
        start.elapsed().as_secs_f64(),
        file.display()
    );
    // The hybrid frame's room, as the main job draws it.
    let room = room_maps(ctx)?;
    if room.compile_s > 0.0 {
        writeln!(
            text,
            "{}: room light maps compiled in {:.1} s",
            ctx.scene.name, room.compile_s
        )?;
    }
    if let Some(dest) = ship {
        for file in shipped::ship(ctx, dest)? {
            writeln!(text, "shipped {}", file.display())?;
        }
    }
    Ok(text)
}

/// Checks every file shipped for `place`'s scene in `assets/compiled/`
/// against the key it would be compiled with today, writing nothing:
/// one `<file>: fresh` line each, or an error naming the stale ones and the
/// command that regenerates them.
pub fn check_shipped(place: &RunPlace) -> Result<String> {
    let scene = Scene::load(&place.scene)?;
    let Some(dir) = shipped::dir(&scene) else {
        bail!(
            "{}: nothing shipped for scene {}",
            shipped::root().join(&scene.name).display(),
            scene.name
        );
    };
    let ctx = CompileContext {
        scene: &scene,
        scene_arg: &place.scene,
        out: &dir,
        size: place.size,
        device: &place.device,
        shipped: Some(dir.clone()),
    };
    let report = shipped::check(&ctx)?;
    let stale: Vec<&str> = report
        .iter()
        .filter(|(_, fresh)| !fresh.is_empty() && fresh != "fresh")
        .map(|(line, _)| line.as_str())
        .collect();
    let mut text = String::new();
    for (line, fresh) in &report {
        writeln!(text, "{line}: {fresh}")?;
    }
    if !stale.is_empty() {
        bail!(
            "{text}the shipped compiled scene no longer matches its inputs; regenerate it with \
             `cargo run --release -p engine -- compile --scene {} --ship {}`",
            place.scene,
            dir.display()
        );
    }
    Ok(text)
}

/// "3, 4, 5, … (17 in all)".
fn preview(samples: &[u32]) -> String {
    let head: Vec<String> = samples.iter().take(6).map(u32::to_string).collect();
    if samples.len() > 6 {
        format!("{}, … ({} in all)", head.join(", "), samples.len())
    } else {
        head.join(", ")
    }
}
