//! Tracing the gold standard: one sample, every sample (skipping those
//! already traced from the same inputs) or a free view, each image keyed
//! by what made it; and the traced layers a sample's inference needs,
//! traced again when missing, stale or damaged.

use crate::maps::{traced_stem, view_stem};
use crate::util::files::claim_dir;
use anyhow::{Context, Result};
use glam::Vec3;
use inference::key::{Freshness, Key};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer, cache, output};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Which views to trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TraceViews {
    /// One orbit sample.
    Sample(u32),
    /// Every orbit sample, skipping those already traced from the same inputs.
    All,
    /// A free view: orbit azimuth and elevation above the orbit plane (degrees).
    Free {
        azimuth_deg: f32,
        elevation_deg: f32,
    },
}

/// Traces `views` of `scene` into `out`; returns the report, ending
/// `rays: N, Mrays/s: X`.
pub fn trace(
    scene: &Scene,
    views: TraceViews,
    settings: &TraceSettings,
    out: &Path,
) -> Result<String> {
    // Everything the user can get wrong is checked before the first file is touched.
    settings.validate()?;
    let tracer = Tracer::new(scene)?;
    let jobs: Vec<(PathBuf, Vec3)> = match views {
        TraceViews::All => (0..scene.orbit.sample_count())
            .map(|k| Ok((traced_stem(out, k), tracer.sample_eye(k)?)))
            .collect::<Result<_>>()?,
        TraceViews::Sample(k) => vec![(traced_stem(out, k), tracer.sample_eye(k)?)],
        TraceViews::Free {
            azimuth_deg,
            elevation_deg,
        } => vec![(
            view_stem(out, azimuth_deg, elevation_deg),
            scene.orbit.eye(azimuth_deg, elevation_deg),
        )],
    };
    claim_dir(out)?;
    let scene_key = cache::scene_key(scene);
    let mut report = format!(
        "{}: {} triangles, BVH built in {:.1} ms\n",
        scene.name,
        tracer.triangle_count(),
        tracer.bvh_build_time().as_secs_f64() * 1e3
    );
    let (mut rays, mut elapsed, mut skipped) = (0u64, Duration::ZERO, 0);
    for (stem, eye) in jobs {
        let key = cache::image_key(&scene_key, eye, settings);
        if views == TraceViews::All && cache::freshness(&stem, &key) == Freshness::Fresh {
            skipped += 1;
            continue;
        }
        let image = tracer.render(eye, settings)?;
        output::write_image(&stem, &image)
            .with_context(|| format!("writing {}", stem.display()))?;
        cache::record(&stem, &key, Some(image.elapsed.as_secs_f64()))?;
        report += &format!(
            "{}: {:.2} s, {} rays, {:.2} Mrays/s\n",
            output::with_suffix(&stem, ".exr").display(),
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

/// The traced layers of the image at `stem` seen from `eye`, tracing it
/// first when missing, traced from other inputs, or damaged (a file that
/// fails its checksum or does not parse is traced again, never trusted).
pub fn traced_layers(
    tracer: &Tracer,
    scene_key: &Key,
    eye: Vec3,
    settings: &TraceSettings,
    stem: &Path,
) -> Result<(Vec<output::ExrLayer>, Key)> {
    let key = cache::image_key(scene_key, eye, settings);
    let (layers, _) = cached_or_traced(stem, &key, || Ok(tracer.render(eye, settings)?))?;
    Ok((layers, key))
}

/// The layers of `<stem>.exr` if it is whole and was traced with `key`,
/// else `trace()`'s image written there (with its record) and read back.
/// Returns whether it traced.
pub fn cached_or_traced(
    stem: &Path,
    key: &Key,
    trace: impl FnOnce() -> Result<inference::trace::TraceImage>,
) -> Result<(Vec<output::ExrLayer>, bool)> {
    let exr = output::with_suffix(stem, ".exr");
    let read = || -> Result<Vec<output::ExrLayer>> {
        let bytes = inference::key::read_verified(&exr).map_err(anyhow::Error::msg)?;
        Ok(output::parse_exr(&bytes, &exr)?)
    };
    match cache::freshness(stem, key) {
        Freshness::Fresh => match read() {
            Ok(layers) => return Ok((layers, false)),
            Err(e) => eprintln!("{e:#}: tracing it again"),
        },
        Freshness::Broken(why) => eprintln!("{why}: tracing it again"),
        Freshness::Missing | Freshness::Stale(_) => {}
    }
    if let Some(dir) = stem.parent() {
        claim_dir(dir)?;
    }
    let image = trace()?;
    output::write_image(stem, &image).with_context(|| format!("writing {}", stem.display()))?;
    cache::record(stem, key, Some(image.elapsed.as_secs_f64()))?;
    Ok((read()?, true))
}
