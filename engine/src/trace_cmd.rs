//! `engine trace`: the gold-standard tracer from the command line (no Vulkan involved).

use crate::cli::TraceArgs;
use crate::play::prepare_output;
use anyhow::{Context, Result};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer, cache, output};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Output folder: `--out`, else `out/<scene>/trace`.
fn output_dir(args: &TraceArgs, scene: &Scene) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("trace"))
}

/// Traces what `args` asks for; returns the report, ending `rays: N, Mrays/s: X`.
pub fn trace(args: &TraceArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let tracer = Tracer::new(&scene)?;
    let settings = TraceSettings {
        width: args.size.0,
        height: args.size.1,
        spp: args.spp.unwrap_or(inference::trace::DEFAULT_SPP),
        seed: args.seed,
        threads: args.threads,
        progress: true,
        ..TraceSettings::default()
    };
    // Everything the user can get wrong is checked before the first file is touched.
    settings.validate()?;
    let jobs: Vec<(PathBuf, glam::Vec3)> = if args.all {
        (0..scene.orbit.samples)
            .map(|k| Ok((format!("sample_{k:04}"), tracer.sample_eye(k)?)))
            .collect::<Result<Vec<_>, inference::trace::TraceError>>()?
            .into_iter()
            .map(|(name, eye)| (PathBuf::from(name), eye))
            .collect()
    } else if let Some(k) = args.sample {
        vec![(format!("sample_{k:04}").into(), tracer.sample_eye(k)?)]
    } else {
        let angle = args.view_angle.unwrap_or(scene.orbit.start_deg);
        let eye = scene.orbit.eye(angle, args.elevation);
        let name = format!("view_az{angle:+.3}_el{:+.3}", args.elevation);
        vec![(name.into(), eye)]
    };
    let out = output_dir(args, &scene);
    prepare_output(&out)?;

    let mut report = format!(
        "{}: {} triangles, BVH built in {:.1} ms\n",
        scene.name,
        tracer.triangle_count(),
        tracer.bvh_build_time().as_secs_f64() * 1e3
    );
    let (mut rays, mut elapsed, mut skipped) = (0u64, Duration::ZERO, 0);
    for (name, eye) in jobs {
        let stem = out.join(name);
        let key = cache::key(&scene, eye, &settings);
        if args.all && cache::is_fresh(&stem, key) {
            skipped += 1;
            continue;
        }
        let image = tracer.render(eye, &settings)?;
        let (exr, _png) = output::write_image(&stem, &image)
            .with_context(|| format!("writing {}", stem.display()))?;
        cache::record(&stem, key)?;
        report += &format!(
            "{}: {:.2} s, {} rays, {:.2} Mrays/s\n",
            exr.display(),
            image.elapsed.as_secs_f64(),
            image.rays,
            image.mrays_per_s()
        );
        rays += image.rays;
        elapsed += image.elapsed;
    }
    if skipped > 0 {
        report += &format!("{skipped} samples already traced with the same inputs: skipped\n");
    }
    let mrays = if elapsed.is_zero() {
        0.0
    } else {
        rays as f64 / elapsed.as_secs_f64() / 1e6
    };
    report += &format!("rays: {rays}, Mrays/s: {mrays:.2}\n");
    Ok(report)
}
