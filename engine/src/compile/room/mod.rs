//! The room's inferred light maps, compiled by the main job like the maps:
//! one view-independent texture per diffuse object (floor, walls, ceiling,
//! any Lambertian object of the scene file), solved once from a stacked set
//! of traced views, keyed by what made it and cached under
//! `<out>/room/` (`<object>.light.exr` and `<object>.light.json`, each with
//! its `.key` record). The room pass multiplies each with the object's own
//! albedo texture (`passes::room`, `RoomStyle::Inferred`).
//!
//! What decides a light map (`inference::lightmap`): where a dense grid of
//! views over the viewpoint space sees each surface and how finely (the
//! thesis's resolution rule, per chart), and which views are traced and
//! stacked into the factored solve (`inference::infer::factored`).

mod solve;
mod store;

use super::CompileContext;
use crate::maps::DataDirs;
use anyhow::Result;
use glam::Vec2;
use inference::key::{Fnv, Freshness, Key};
use inference::lightmap::{ObjectLightmap, Rule, plan, solve_views, survey, survey_views};
use inference::trace::bvh::SceneBvh;
use inference::trace::{TraceSettings, cache};
use std::hash::Hasher;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Bumped when the light maps change for the same inputs (2: solved for
/// the room pass's nearest-MIP-level reads; 3: for its patterns drawn in
/// closed form).
const ROOM_MAPS_VERSION: u64 = 3;
/// One surveyed ray per this many pixels in x and in y.
const SURVEY_STRIDE: u32 = 4;

/// One diffuse object's light map, ready to upload.
#[derive(Clone, Debug)]
pub struct ObjectRoomMap {
    /// Index in `scene.objects`.
    pub object: usize,
    pub width: u32,
    pub height: u32,
    /// Every MIP level, finest first, RGBA (A = 1): the solved chain.
    pub texels: Vec<[f32; 4]>,
    pub levels: u32,
    /// Light-map coordinates of each of the object's vertices.
    pub uvs: Vec<Vec2>,
}

/// The light maps of every diffuse object some view sees.
#[derive(Clone, Debug, Default)]
pub struct RoomMaps {
    pub objects: Vec<ObjectRoomMap>,
    /// Seconds spent compiling (0 when every map was fresh).
    pub compile_s: f64,
}

/// `<out>/room`: where the light maps and their traced views live.
pub fn room_dir(out: &Path) -> PathBuf {
    out.join("room")
}

/// Every diffuse object's light map, compiled first when missing, stale or
/// damaged (each object on its own; fresh ones are only read).
pub fn room_maps(ctx: &CompileContext) -> Result<RoomMaps> {
    let scene = ctx.scene;
    let dirs = DataDirs::under(ctx.out, scene);
    let req = ctx.request(&dirs, false);
    let settings = req.trace_settings()?;
    let dir = room_dir(ctx.out);
    let start = Instant::now();
    let bvh = SceneBvh::build(scene);
    let eyes: Vec<_> = survey_views(&scene.orbit)
        .iter()
        .map(|v| v.eye(&scene.orbit))
        .collect();
    let sights = survey(scene, &bvh, &eyes, ctx.size, SURVEY_STRIDE);
    let rule = Rule::default();
    let key = maps_key(scene, &settings, &rule, req.eps_f);
    let mut out = RoomMaps::default();
    let mut stale = Vec::new();
    for sight in &sights {
        let name = &scene.objects[sight.object].name;
        let Some(layout) = plan(name, sight, &rule) else {
            continue; // no view sees it: drawn with its albedo alone
        };
        match store::load(&dir, &layout, &sight.charts, sight.object, &key) {
            Ok(map) => out.objects.push(map),
            Err(why) => match shipped_map(ctx, &layout, sight, &key) {
                Some(map) => out.objects.push(map),
                None => stale.push((sight, layout, why)),
            },
        }
    }
    if !stale.is_empty() {
        let names: Vec<String> = stale
            .iter()
            .map(|(s, _, why)| format!("{} ({why})", scene.objects[s.object].name))
            .collect();
        eprintln!(
            "{}: compiling the room's light maps: {} (cached; a re-run resumes)",
            scene.name,
            names.join(", ")
        );
        crate::util::files::claim_dir(&dir)?;
        let mut solver = solve::Solver::new(ctx, &settings, &dir, req.solve_options())?;
        let views = solve_views(&scene.orbit);
        for (sight, layout, _) in stale {
            let solved = solver.solve(sight, &layout, &views)?;
            store::save(&dir, &layout, &solved.result, &key)?;
            eprintln!("{}", solved.summary);
            let map = store::load(&dir, &layout, &sight.charts, sight.object, &key)
                .map_err(anyhow::Error::msg)?;
            out.objects.push(map);
        }
        out.compile_s = start.elapsed().as_secs_f64();
    }
    out.objects.sort_by_key(|m| m.object);
    Ok(out)
}

/// The key every light map of `ctx`'s scene carries when compiled today.
pub fn expected_key(ctx: &CompileContext) -> Result<Key> {
    let dirs = DataDirs::under(ctx.out, ctx.scene);
    let req = ctx.request(&dirs, false);
    Ok(maps_key(
        ctx.scene,
        &req.trace_settings()?,
        &Rule::default(),
        req.eps_f,
    ))
}

/// `layout`'s light map from the shipped compiled scene, when its key
/// matches (read only; a stale shipped map is compiled under --out).
fn shipped_map(
    ctx: &CompileContext,
    layout: &ObjectLightmap,
    sight: &inference::lightmap::ObjectSight,
    key: &Key,
) -> Option<ObjectRoomMap> {
    let dir = room_dir(ctx.shipped.as_ref()?);
    store::load(&dir, layout, &sight.charts, sight.object, key).ok()
}

/// What every light map of `scene` depends on: the scene (through the
/// traced views' keys: geometry, materials, lights, tracer version,
/// settings), the surveyed and stacked viewpoints, the rule and the solve.
fn maps_key(
    scene: &inference::scene::Scene,
    settings: &TraceSettings,
    rule: &Rule,
    eps_f: f32,
) -> Key {
    let scene_key = cache::scene_key(scene);
    let mut views = Fnv::default();
    for v in solve_views(&scene.orbit)
        .iter()
        .chain(&survey_views(&scene.orbit))
    {
        let eye = v.eye(&scene.orbit);
        views.write_u64(cache::image_key(&scene_key, eye, settings).hash());
    }
    let mut r = Fnv::default();
    for x in [rule.jacobian, rule.magnification, rule.margin_m, eps_f] {
        r.f32(x);
    }
    for x in [rule.min_size, rule.max_size, rule.gutter, SURVEY_STRIDE] {
        r.write_u32(x);
    }
    Key::new()
        .with("room maps version", ROOM_MAPS_VERSION)
        .with("views", views.finish())
        .with("rule and solve", r.finish())
}

/// Whether a light map on disk can be used (for messages).
pub(crate) fn describe(f: &Freshness) -> String {
    match f {
        Freshness::Fresh => "fresh".into(),
        Freshness::Missing => "missing".into(),
        Freshness::Stale(what) => format!("{} changed", what.join(", ")),
        Freshness::Broken(why) => why.clone(),
    }
}

/// The light map's texture layout (the full MIP chain the solve fills).
pub(crate) fn layout_of(map: &ObjectLightmap) -> inference::solve::layout::TextureLayout {
    inference::solve::layout::TextureLayout::full_chain(
        inference::solve::layout::TextureShape::Tex2D {
            width: map.width,
            height: map.height,
        },
    )
}
