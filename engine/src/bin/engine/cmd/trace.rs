//! `engine trace`: the gold-standard tracer (CPU, no Vulkan).

use super::default_dir;
use crate::cli::TraceArgs;
use anyhow::{Result, bail};
use engine::compile::trace::{TraceViews, trace};
use inference::scene::Scene;
use inference::trace::TraceSettings;

pub fn run(args: &TraceArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let settings = TraceSettings {
        width: args.size.0,
        height: args.size.1,
        spp: args.spp.unwrap_or(inference::trace::DEFAULT_SPP),
        seed: args.seed,
        threads: args.threads,
        progress: true,
        ..TraceSettings::default()
    };
    if args.elevation.is_some() && args.view_angle.is_none() {
        bail!(
            "--elevation places a free view: it needs --view-angle (orbit samples have their own elevation)"
        );
    }
    let views = match (args.all, args.sample, args.view_angle) {
        (true, ..) => TraceViews::All,
        (_, Some(k), _) => TraceViews::Sample(k),
        _ => TraceViews::Free {
            azimuth_deg: args.view_angle.unwrap_or(scene.orbit.start_deg),
            elevation_deg: args.elevation.unwrap_or(0.0),
        },
    };
    trace(
        &scene,
        views,
        &settings,
        &default_dir(&args.out, &scene, "trace"),
    )
}
