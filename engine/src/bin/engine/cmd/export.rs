//! `engine export --ktx2 DIR`: every sample's inferred maps as KTX2 files
//! and a JSON sidecar other engines read.

use super::default_dir;
use crate::cli::ExportArgs;
use anyhow::Result;
use inference::scene::Scene;

pub fn run(args: &ExportArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let infer_dir = default_dir(&args.infer_dir, &scene, "infer");
    Ok(engine::export::export_ktx2(&scene, &infer_dir, &args.ktx2)?.summary())
}
