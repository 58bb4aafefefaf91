//! One module per subcommand: each turns its arguments into the library's
//! typed options, runs the driver, and returns what to print.

pub mod bench;
pub mod codec_report;
pub mod compile;
pub mod encode;
pub mod eval;
pub mod export;
pub mod infer;
pub mod place;
pub mod play;
pub mod relight;
pub mod trace;

use inference::scene::Scene;
use std::path::{Path, PathBuf};

/// `given`, else `out/<scene>/<sub>` under the current folder.
fn default_dir(given: &Option<PathBuf>, scene: &Scene, sub: &str) -> PathBuf {
    given.clone().unwrap_or_else(|| {
        let base = Path::new("out").join(&scene.name);
        if sub.is_empty() { base } else { base.join(sub) }
    })
}
