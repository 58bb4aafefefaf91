//! Layered shells (thesis §6.3): where objects stand near the glass, LBG
//! places more shells than the room's box (`inference::glass::placement`).
//! Each layer's map is traced from the lens centroid with the lens and the
//! nearer layers' objects transparent — inner layers premultiplied RGBA
//! with their objects' coverage in alpha, the outermost opaque — and cached
//! beside the room shell map with a content key. Hybrid frames read the
//! layers nearest first, each "over" the ones behind it.

use super::shell::{cached_map, shell_key, shell_settings};
use anyhow::Result;
use glam::Vec3;
use inference::glass::ShellSet;
use inference::glass::shell_map::{LayerObjects, trace_layer_map};
use inference::key::{Fnv, Key};
use inference::scene::Scene;
use inference::trace::Tracer;
use std::hash::Hasher;
use std::path::{Path, PathBuf};

/// Bumped when what a layer map holds changes.
const LAYER_VERSION: u64 = 1;

/// Bumped when the placement changes for the same inputs.
const PLACEMENT_VERSION: u64 = 1;

/// Where the placed shells are cached under `out`.
pub fn placement_path(out: &Path) -> PathBuf {
    out.join("glass").join("shells.json")
}

/// The shells of `lens` in `scene` (at most `max_shells`): read from `out`
/// when fresh, else placed ([`inference::glass::placement`]) and written.
/// Returns them with the seconds spent placing (0 when read).
pub fn placed_shells(
    scene: &Scene,
    out: &Path,
    lens: &inference::glass::Lens,
    max_shells: u32,
) -> Result<(ShellSet, f64)> {
    let file = placement_path(out);
    let key = inference::trace::cache::scene_key(scene)
        .with("glass shells", PLACEMENT_VERSION)
        .with("lens", u64::from(lens.object))
        .with("max shells", u64::from(max_shells));
    if inference::key::freshness(&file, &key) == inference::key::Freshness::Fresh {
        let read = inference::key::read_verified(&file)
            .and_then(|b| serde_json::from_slice::<ShellSet>(&b).map_err(|e| e.to_string()));
        match read {
            Ok(set) => return Ok((set, 0.0)),
            Err(why) => eprintln!("{}: {why}: placing the shells again", file.display()),
        }
    }
    crate::util::files::check_overwrite_keyed(&file)?;
    let start = std::time::Instant::now();
    let set = inference::glass::placement::place_for_scene(scene, lens, max_shells as usize);
    let seconds = start.elapsed().as_secs_f64();
    if let Some(dir) = file.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("creating {}: {e}", dir.display()))?;
    }
    inference::files::write_bytes(&file, &serde_json::to_vec_pretty(&set)?)?;
    inference::key::write_record(&file, &key)?;
    Ok((set, seconds))
}

/// Where layer `i`'s map is cached under `out`.
pub fn layer_path(out: &Path, i: usize) -> PathBuf {
    out.join("glass").join(format!("layer_{i}.bin"))
}

/// What layer `i` of `set` around lens `skip` depends on: what the room
/// shell map does, the shells (their shapes decide which objects each
/// layer holds) and the layer's place among them.
pub fn layer_key(scene: &Scene, skip: u32, set: &ShellSet, i: usize, size: u32) -> Key {
    let mut h = Fnv::default();
    h.str(&serde_json::to_string(set).unwrap_or_default());
    shell_key(scene, skip, set.origin(), size)
        .with("glass layer", LAYER_VERSION)
        .with("shells", h.finish())
        .with("layer", i as u64)
}

/// The objects layer `i` of `set` sees: its own (None for the outermost,
/// which holds whatever lies past the nearer layers), the lens and the
/// nearer layers' objects transparent.
fn layer_objects(set: &ShellSet, lens: u32, i: usize) -> (Vec<u32>, Option<Vec<u32>>) {
    let mut hidden = vec![lens];
    hidden.extend(
        set.shells[..i]
            .iter()
            .flat_map(|s| s.objects.iter().copied()),
    );
    let own = (i + 1 < set.shells.len()).then(|| set.shells[i].objects.clone());
    (hidden, own)
}

/// Every layer's map of `set` (nearest first), `size`² per face, as f16
/// RGBA bytes in upload order: read from `out` when fresh, else traced.
pub fn layer_maps(
    scene: &Scene,
    out: &Path,
    lens: u32,
    set: &ShellSet,
    size: u32,
) -> Result<Vec<Vec<u8>>> {
    let mut tracer: Option<Tracer> = None;
    let origin: Vec3 = set.origin();
    let n = set.shells.len();
    (0..n)
        .map(|i| {
            let key = layer_key(scene, lens, set, i, size);
            let what = format!("shell layer {} of {n}", i + 1);
            cached_map(&layer_path(out, i), &key, size, &what, || {
                // One tracer (and photon map) for every layer traced.
                let tracer = match &mut tracer {
                    Some(t) => t,
                    slot @ None => slot.insert(Tracer::new(scene)?),
                };
                let (hidden, own) = layer_objects(set, lens, i);
                let layer = LayerObjects {
                    hidden: &hidden,
                    own: own.as_deref(),
                };
                let settings = shell_settings(size);
                Ok(trace_layer_map(tracer, &layer, origin, size, &settings))
            })
        })
        .collect()
}

/// Places the shells of the scene's glass object and, when objects stand
/// near the glass (more than the room's one shell), has hybrid frames
/// composite their layer maps (traced under `out` when missing). Returns
/// the layers hybrid frames read (1: the room's box alone).
pub fn load(renderer: &mut crate::renderer::Renderer, scene: &Scene, out: &Path) -> Result<u32> {
    let Some(g) = renderer.glass.as_ref() else {
        return Ok(1);
    };
    let lens = g.lens();
    let Some(object) = scene.objects.get(lens.object as usize) else {
        return Ok(1);
    };
    let settings = object.glass.clone().unwrap_or_default();
    let (set, placed_s) = placed_shells(scene, out, &lens, settings.shells)?;
    let n = set.shells.len();
    if n < 2 {
        return Ok(1);
    }
    let size = g.shell_map().desc.width;
    let maps = layer_maps(scene, out, lens.object, &set, size)?;
    renderer.load_glass_layers(&maps, &set)?;
    let names: Vec<String> = set
        .shells
        .iter()
        .map(|s| {
            let objects: Vec<&str> = s
                .objects
                .iter()
                .filter_map(|&o| scene.objects.get(o as usize).map(|o| o.name.as_str()))
                .collect();
            format!(
                "{} at {:.2} m ({})",
                shape_name(&s.shape),
                s.distance,
                objects.join(", ")
            )
        })
        .collect();
    let placed = match placed_s {
        0.0 => String::new(),
        s => format!("placed in {s:.2} s; "),
    };
    eprintln!(
        "hybrid glass reads {n} shell layers, nearest first: {} ({placed}--traced-shell: the one room shell)",
        names.join("; ")
    );
    Ok(n as u32)
}

fn shape_name(shape: &inference::glass::ShellShape) -> &'static str {
    use inference::glass::ShellShape;
    match shape {
        ShellShape::Sphere { .. } => "sphere",
        ShellShape::Cylinder { .. } => "cylinder",
        ShellShape::Quad { .. } => "quad",
        ShellShape::Box { .. } => "the room's box",
        ShellShape::Infinity => "infinity",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use inference::glass::{Shell, ShellShape};

    fn shell(objects: Vec<u32>) -> Shell {
        Shell {
            shape: ShellShape::Sphere { radius: 1.0 },
            objects,
            distance: 1.0,
        }
    }

    #[test]
    fn each_layer_sees_past_the_nearer_ones_and_the_outermost_holds_the_rest() {
        let set = ShellSet {
            origin: [0.0; 3],
            shells: vec![shell(vec![4]), shell(vec![5, 6]), shell(vec![0, 1])],
        };
        assert_eq!(layer_objects(&set, 9, 0), (vec![9], Some(vec![4])));
        assert_eq!(layer_objects(&set, 9, 1), (vec![9, 4], Some(vec![5, 6])));
        assert_eq!(layer_objects(&set, 9, 2), (vec![9, 4, 5, 6], None));
    }
}
