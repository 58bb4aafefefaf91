//! `engine encode`: every sample's inferred maps into one container.

use super::default_dir;
use crate::cli::EncodeArgs;
use anyhow::{Result, bail};
use codec::Target;
use engine::compile::container_key;
use engine::compile::encode::{
    DEFAULT_RATIO, MapsFor, check_ratio, encode_to, load_input, map_keys, orbit_grid,
};
use engine::maps::MapSet;
use inference::scene::Scene;

pub fn run(args: &EncodeArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let target = match (args.ratio, args.bytes) {
        (Some(r), None) => {
            check_ratio(r)?;
            Target::Ratio(r)
        }
        (None, Some(b)) if b > 0 => Target::Bytes(b),
        (None, None) => Target::Ratio(DEFAULT_RATIO),
        (None, Some(_)) => bail!("--bytes 0: expected a container size above 0 bytes"),
        (Some(_), Some(_)) => bail!("--ratio and --bytes: give one target, not both"),
    };
    engine::util::files::check_folder_exists(&args.out)?;
    let dir = default_dir(&args.infer_dir, &scene, "infer");
    // The container's key is made of the keys its maps were inferred with.
    let keys = map_keys(&scene, MapSet::Scene, &dir, MapsFor::Encode)?;
    let input = load_input(&scene, MapSet::Scene, &dir, MapsFor::Encode)?;
    let e = encode_to(
        &input,
        target,
        &args.out,
        &container_key(keys.iter(), target, orbit_grid(&scene.orbit)),
        // The compile's budget needs its traces too: the main job records it.
        None,
    )?;
    Ok(format!(
        "{}: {} textures x {} samples, {} bytes from {} raw (ratio {:.1}:1, worst texture {:.1} dB) in {:.1} s{}\n",
        args.out.display(),
        input.textures.len(),
        scene.orbit.sample_count(),
        e.bytes,
        e.raw_bytes,
        e.ratio,
        e.worst_psnr_db,
        e.seconds,
        e.note.map_or(String::new(), |n| format!(" ({n})"))
    ))
}
