//! A light map on disk: `<object>.light.exr` (every MIP level, RGB float)
//! and `<object>.light.json` (its layout: size and where each chart sits),
//! each with the key record of what made it, written atomically.

use super::{ObjectRoomMap, describe, layout_of};
use anyhow::{Context, Result};
use inference::infer::factored::FactoredResult;
use inference::infer::maps::{parse_map, write_map};
use inference::key::{Freshness, Key, freshness, read_verified, write_record};
use inference::lightmap::{Charts, ObjectLightmap};
use std::path::{Path, PathBuf};

const CHANNELS: usize = 3;

fn paths(dir: &Path, object: &str) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("{object}.light.exr")),
        dir.join(format!("{object}.light.json")),
    )
}

/// Writes `result` as `plan.object`'s light map, with `key`.
pub fn save(dir: &Path, plan: &ObjectLightmap, result: &FactoredResult, key: &Key) -> Result<()> {
    crate::util::files::claim_dir(dir)?;
    let (exr, json) = paths(dir, &plan.object);
    write_map(&exr, &result.layout, &result.map)
        .with_context(|| format!("writing {}", exr.display()))?;
    write_record(&exr, key)?;
    crate::util::files::write_json(&json, plan)?;
    write_record(&json, key)?;
    Ok(())
}

/// `plan.object`'s light map if both files are whole, made with `key` and
/// laid out as `plan`; else why not (missing, stale, damaged).
pub fn load(
    dir: &Path,
    plan: &ObjectLightmap,
    charts: &Charts,
    object: usize,
    key: &Key,
) -> Result<ObjectRoomMap, String> {
    let (exr, json) = paths(dir, &plan.object);
    for file in [&exr, &json] {
        match freshness(file, key) {
            Freshness::Fresh => {}
            f => return Err(describe(&f)),
        }
    }
    let text = read_verified(&json)?;
    let stored: ObjectLightmap = serde_json::from_slice(&text)
        .map_err(|e| format!("{}: expected a light-map layout ({e})", json.display()))?;
    if stored != *plan {
        return Err(format!("{}: laid out for other views", json.display()));
    }
    let layout = layout_of(plan);
    let bytes = read_verified(&exr)?;
    let map = parse_map(&bytes, &exr, &layout, CHANNELS).map_err(|e| e.to_string())?;
    let texels = (0..layout.len())
        .map(|i| [map[0][i], map[1][i], map[2][i], 1.0])
        .collect();
    Ok(ObjectRoomMap {
        object,
        width: plan.width,
        height: plan.height,
        texels,
        levels: layout.levels(),
        uvs: plan.uvs(charts),
    })
}
