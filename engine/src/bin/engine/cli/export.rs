//! `engine export`'s command line.

use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    /// Folder for the KTX2 files and maps.json (made if missing; refused
    /// when it holds files the engine did not write).
    #[arg(long)]
    pub ktx2: PathBuf,
    /// A built-in scene's name (teapot, teapot_split, teapot_rings, glass,
    /// glass_near, brass) or the path of a .toml scene file.
    #[arg(long, default_value = "teapot")]
    pub scene: String,
    /// Where the maps were inferred [default: out/<scene>/infer, where
    /// `engine infer --all` and a compile that infers put them; the main
    /// job playing a shipped compiled scene infers none].
    #[arg(long)]
    pub infer_dir: Option<PathBuf>,
}
