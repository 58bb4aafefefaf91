//! What the main job compiles before it can play PEMs: the traced gold
//! standard, the inferred maps of every sample and the compressed
//! container — each only when missing, stale or damaged, each with its own
//! progress bars and key records, so a second run starts playing at once
//! and an edited scene is never played from old maps.

pub mod encode;
pub mod glass_shells;
pub mod infer;
pub mod room;
pub mod scene;
pub mod shard;
pub mod shipped;
pub mod trace;

use crate::backend::DeviceOptions;
use crate::maps::{DataDirs, MapLayer, MapSet, map_path};
use crate::options::{Maps, PemOptions};
use crate::pem::source::MapSource;
use anyhow::{Result, bail};
use infer::{InferRequest, Plan};
use inference::key::{Fnv, Freshness, Key};
use inference::scene::Scene;
use std::hash::Hasher;
use std::path::Path;

/// Where and how a run compiles: the scene (and how the user named it, for
/// hints), the output folder, the image size and the device.
pub struct CompileContext<'a> {
    pub scene: &'a Scene,
    pub scene_arg: &'a str,
    pub out: &'a Path,
    pub size: (u32, u32),
    pub device: &'a DeviceOptions,
    /// The compiled data shipped for this scene (`assets/compiled/<scene>`),
    /// played when its keys match; None with `--recompile`.
    pub shipped: Option<std::path::PathBuf>,
}

impl CompileContext<'_> {
    fn request(&self, dirs: &DataDirs, sphere: bool) -> InferRequest {
        InferRequest {
            sphere,
            size: self.size,
            device: self.device.clone(),
            ..InferRequest::all(self.scene, dirs.trace.clone(), dirs.infer.clone())
        }
    }
}

/// The key of a container: the keys of the maps it holds, the codec's
/// format, the target it was encoded at and, for a 2D viewpoint space, its
/// parameter grid (1D containers keep the key they always had).
pub fn container_key<'k>(
    map_keys: impl Iterator<Item = &'k Key>,
    target: codec::Target,
    grid: codec::ParamGrid,
) -> Key {
    let mut h = Fnv::default();
    for k in map_keys {
        h.write_u64(k.hash());
    }
    let target = match target {
        codec::Target::Ratio(r) => r.to_bits(),
        codec::Target::Bytes(b) => b ^ (1 << 63),
    };
    let key = Key::new()
        .with("maps", h.finish())
        .with("codec format", u64::from(codec::FORMAT_VERSION))
        .with("target", target);
    if grid.dims() == 2 {
        key.with(
            "parameter grid",
            u64::from(grid.n0) << 32 | u64::from(grid.n1),
        )
    } else {
        key
    }
}

/// The map source for `layers` under `pem`'s options, compiling whatever is
/// missing, stale or damaged under the output folder first. Maps or a
/// container the user named (`--infer-dir`, `--container`) are inputs:
/// read, checked, never rebuilt. The sphere PEM's maps, asked for by
/// `layers`, have their own container under the output folder
/// ([`MapSet::Sphere`]; `--container` names the scene's).
pub fn map_source(
    ctx: &CompileContext,
    pem: &PemOptions,
    layers: &[MapLayer],
) -> Result<MapSource> {
    let scene = ctx.scene;
    let mut dirs = DataDirs::under(ctx.out, scene);
    if let Some(d) = &pem.infer_dir {
        dirs.infer = d.clone();
    }
    let set = MapSet::of(layers);
    let req = ctx.request(&dirs, set == MapSet::Sphere);
    let plan = Plan::new(scene, &req)?;
    let wanted: Vec<MapLayer> = if pem.maps == Maps::Exr {
        layers.to_vec()
    } else {
        set.specs(scene).iter().map(|s| s.layer).collect()
    };
    let stale = stale_maps(&plan, &req, &wanted)?;
    let named = pem.container.as_ref().filter(|_| set == MapSet::Scene);
    let plays_container = pem.maps == Maps::Container;
    if !stale.is_empty() && plays_container && pem.infer_dir.is_none() && named.is_none() {
        // A fresh container needs no maps: the one under --out, else the
        // shipped one.
        let key = expected_container_key(ctx, &plan, &req, set)?;
        let path = dirs.container_of(set);
        if inference::key::freshness(&path, &key) == Freshness::Fresh {
            return MapSource::container_of(scene, set, &path);
        }
        if set == MapSet::Scene
            && let Some(path) = shipped::container(ctx, &key)
        {
            // Read only: a shipped file that fails to read is passed over.
            match MapSource::container(scene, &path) {
                Ok(source) => {
                    eprintln!(
                        "{}: playing the shipped compiled scene {} (its key matches; --recompile compiles it here)",
                        scene.name,
                        path.display()
                    );
                    return Ok(source);
                }
                Err(e) => eprintln!("{}: {e:#}; compiling instead", path.display()),
            }
        }
    }
    if !stale.is_empty() {
        if pem.infer_dir.is_some() {
            bail!(
                "{}: {} (infer them with `engine infer --scene {} --all --out {}`, or drop --infer-dir to compile under --out)",
                dirs.infer.display(),
                describe(&plan, &stale),
                ctx.scene_arg,
                dirs.infer.display()
            );
        }
        eprintln!(
            "{}: compiling the maps ({}): tracing and inferring what is missing (cached; a re-run resumes)",
            scene.name,
            describe(&plan, &stale)
        );
        eprint!("{}", infer::infer(scene, &req)?);
        let left = stale_maps(&plan, &req, &wanted)?;
        if !left.is_empty() {
            bail!(
                "{}: inference finished but {}",
                dirs.infer.display(),
                describe(&plan, &left)
            );
        }
    }
    if pem.maps == Maps::Exr {
        return Ok(MapSource::exr(&dirs.infer));
    }
    container_source(ctx, named, set, (&plan, &req), &dirs)
}

/// The samples of `ctx`'s scene some map of which is not fresh under its
/// output folder, in order.
pub fn missing_maps(ctx: &CompileContext) -> Result<Vec<u32>> {
    let dirs = DataDirs::under(ctx.out, ctx.scene);
    let req = ctx.request(&dirs, false);
    let plan = Plan::new(ctx.scene, &req)?;
    let mut samples: Vec<u32> = plan
        .stale(&req.samples, &req.infer_dir)?
        .into_iter()
        .map(|s| s.0)
        .collect();
    samples.dedup();
    Ok(samples)
}

/// Traces and infers what is not fresh of `samples` under `ctx`'s output
/// folder (one shard of a farmed compile).
pub fn infer_samples(ctx: &CompileContext, samples: &[u32]) -> Result<String> {
    let dirs = DataDirs::under(ctx.out, ctx.scene);
    let req = InferRequest {
        samples: samples.to_vec(),
        ..ctx.request(&dirs, false)
    };
    infer::infer(ctx.scene, &req)
}

/// (sample, job, what is wrong) for every map of a `wanted` layer that is
/// not fresh.
fn stale_maps(
    plan: &Plan,
    req: &InferRequest,
    wanted: &[MapLayer],
) -> Result<Vec<(u32, usize, Freshness)>> {
    Ok(plan
        .stale(&req.samples, &req.infer_dir)?
        .into_iter()
        .filter(|(_, i, _)| wanted.contains(&plan.jobs[*i].layer))
        .collect())
}

/// "N maps missing; sample 3 teapot.ptm: lights changed".
fn describe(plan: &Plan, stale: &[(u32, usize, Freshness)]) -> String {
    let missing = stale.iter().filter(|s| s.2 == Freshness::Missing).count();
    let mut parts = Vec::new();
    if missing > 0 {
        parts.push(format!("{missing} maps missing"));
    }
    for (k, i, f) in stale.iter().filter(|s| s.2 != Freshness::Missing).take(2) {
        let name = plan.jobs[*i].name();
        parts.push(match f {
            Freshness::Stale(what) => format!("sample {k} {name}: {} changed", what.join(", ")),
            Freshness::Broken(why) => format!("sample {k} {name}: {why}"),
            _ => continue,
        });
    }
    let others = stale.iter().filter(|s| s.2 != Freshness::Missing).count();
    if others > 2 {
        parts.push(format!("{} more stale", others - 2));
    }
    parts.join("; ")
}

/// The key `ctx`'s container carries when compiled today from fresh maps.
pub fn container_key_for(ctx: &CompileContext) -> Result<Key> {
    let dirs = DataDirs::under(ctx.out, ctx.scene);
    let req = ctx.request(&dirs, false);
    let plan = Plan::new(ctx.scene, &req)?;
    expected_container_key(ctx, &plan, &req, MapSet::Scene)
}

/// The key the container of `set` of `req`'s samples carries when encoded
/// from fresh maps at the default ratio.
fn expected_container_key(
    ctx: &CompileContext,
    plan: &Plan,
    req: &InferRequest,
    set: MapSet,
) -> Result<Key> {
    let target = codec::Target::Ratio(encode::DEFAULT_RATIO);
    let mut map_keys = Vec::new();
    for &k in &req.samples {
        let trace_key = plan.trace_key(k)?;
        for spec in set.specs(ctx.scene) {
            if let Some(job) = plan
                .jobs
                .iter()
                .find(|j| j.object.name == spec.object && j.layer == spec.layer)
            {
                map_keys.push(plan.key(k, &trace_key, job));
            }
        }
    }
    let grid = encode::orbit_grid(&ctx.scene.orbit);
    Ok(container_key(map_keys.iter(), target, grid))
}

/// The container of `set`: the one `named` by the user (checked, read
/// only) or the one under the output folder, encoded again when stale or
/// damaged.
fn container_source(
    ctx: &CompileContext,
    named: Option<&std::path::PathBuf>,
    set: MapSet,
    (plan, req): (&Plan, &InferRequest),
    dirs: &DataDirs,
) -> Result<MapSource> {
    let key = expected_container_key(ctx, plan, req, set)?;
    let path = named.cloned().unwrap_or_else(|| dirs.container_of(set));
    match inference::key::freshness(&path, &key) {
        Freshness::Fresh => return MapSource::container_of(ctx.scene, set, &path),
        why if named.is_some() => bail!(
            "{}: {} (encode it with `engine encode --scene {} --out {}`, or drop --container to compile under --out)",
            path.display(),
            match why {
                Freshness::Missing if path.exists() =>
                    "no key record: not a container this engine compiled for these maps".to_string(),
                Freshness::Missing => "no such file".to_string(),
                Freshness::Stale(what) =>
                    format!("compiled from other inputs ({} changed)", what.join(", ")),
                Freshness::Broken(why) => why,
                Freshness::Fresh => unreachable!("handled above"),
            },
            ctx.scene_arg,
            path.display()
        ),
        _ => {}
    }
    let input = load_or_reinfer(ctx, req, dirs, set)?;
    let target = codec::Target::Ratio(encode::DEFAULT_RATIO);
    let budget = infer::inputs_budget(plan, set, &dirs.trace, &dirs.infer);
    let e = encode::encode_to(&input, target, &path, &key, budget.seconds())?;
    eprintln!(
        "{}: {} bytes from {} raw (ratio {:.1}:1, worst texture {:.1} dB) in {:.1} s{}",
        path.display(),
        e.bytes,
        e.raw_bytes,
        e.ratio,
        e.worst_psnr_db,
        e.seconds,
        e.note.map_or(String::new(), |n| format!(" ({n})"))
    );
    eprintln!("{}", budget_line(&budget, e.seconds));
    MapSource::container_of(ctx.scene, set, &path)
}

/// What the container cost to compile, as its record keeps it.
fn budget_line(budget: &infer::Budget, encode_s: f64) -> String {
    let minutes = |s: f64| s / 60.0;
    match budget.seconds() {
        Some(s) => format!(
            "compile time of these maps: {:.1} min (traces {:.1}, inference {:.1}, encode {:.1})",
            minutes(s + encode_s),
            minutes(budget.trace_s),
            minutes(budget.infer_s),
            minutes(encode_s)
        ),
        None => format!(
            "compile time of these maps: unknown ({} inputs were made before times were recorded)",
            budget.untimed
        ),
    }
}

/// The encoder's input of `set`; a map that fails to read (damaged since
/// it was checked) is forgotten and inferred again, once.
fn load_or_reinfer(
    ctx: &CompileContext,
    req: &InferRequest,
    dirs: &DataDirs,
    set: MapSet,
) -> Result<codec::EncodeInput> {
    let load = || encode::load_input(ctx.scene, set, &dirs.infer, encode::MapsFor::Encode);
    match load() {
        Ok(input) => Ok(input),
        Err(e) => {
            let Some(bad) = e.downcast_ref::<encode::BadMap>() else {
                return Err(e);
            };
            eprintln!("{bad}: inferring it again");
            let specs = set.specs(ctx.scene);
            let spec = &specs[bad.spec];
            inference::key::forget(&map_path(&dirs.infer, bad.sample, &spec.object, spec.layer));
            eprint!("{}", infer::infer(ctx.scene, req)?);
            load()
        }
    }
}
