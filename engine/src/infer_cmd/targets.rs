//! Targets from the tracer: layers of a sample (traced on demand), as
//! RGBA pixels, and a reflector's composite appearance.

use crate::play::prepare_output;
use anyhow::{Context, Result, bail};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer, cache, output};
use std::path::Path;

/// The traced layers of sample `k`, tracing them first when missing or
/// traced with other inputs.
pub(super) fn traced_layers(
    trace_dir: &Path,
    scene: &Scene,
    tracer: &Tracer,
    k: u32,
    settings: &TraceSettings,
) -> Result<(Vec<output::ExrLayer>, u64)> {
    let stem = trace_dir.join(format!("sample_{k:04}"));
    let eye = tracer.sample_eye(k)?;
    let key = cache::key(scene, eye, settings);
    if !cache::is_fresh(&stem, key) {
        if let Some(dir) = stem.parent() {
            prepare_output(dir)?;
        }
        let image = tracer.render(eye, settings)?;
        output::write_image(&stem, &image)
            .with_context(|| format!("writing {}", stem.display()))?;
        cache::record(&stem, key)?;
    }
    let path = output::with_suffix(&stem, ".exr");
    Ok((output::read_exr(&path)?, key))
}

/// `name`'s pixels as RGBA (premultiplied by A when `premultiply`).
pub(crate) fn target_pixels(
    layers: &[output::ExrLayer],
    name: &str,
    premultiply: bool,
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>> {
    let (_, channels) = layers
        .iter()
        .find(|(n, _)| n == name)
        .with_context(|| format!("traced image has no layer {name:?}"))?;
    let get = |c: &str| channels.iter().find(|(n, _)| n == c).map(|(_, v)| v);
    let (Some(r), Some(g), Some(b)) = (get("R"), get("G"), get("B")) else {
        bail!("layer {name:?}: expected channels R, G, B");
    };
    if r.len() != pixel_count {
        bail!(
            "layer {name:?}: {} pixels, the probe renders have {pixel_count} (trace at the same --size)",
            r.len()
        );
    }
    let a = get("A");
    Ok((0..pixel_count)
        .map(|i| {
            let alpha = a.map_or(1.0, |a| a[i]);
            let k = if premultiply { alpha } else { 1.0 };
            [r[i] * k, g[i] * k, b[i] * k, alpha]
        })
        .collect())
}

/// The reflector's own appearance from its layers, as the runtime
/// composites it: `fresnel × (local over distant)` (+ diffuse if any).
pub(crate) fn composite_pixels(
    layers: &[output::ExrLayer],
    object: &str,
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>> {
    let fresnel = target_pixels(layers, &format!("{object}.fresnel"), false, pixel_count)?;
    let distant = target_pixels(
        layers,
        &format!("{object}.specular_distant"),
        false,
        pixel_count,
    )?;
    let local = target_pixels(
        layers,
        &format!("{object}.specular_local"),
        true,
        pixel_count,
    )
    .ok();
    let diffuse = target_pixels(layers, &format!("{object}.diffuse"), false, pixel_count).ok();
    Ok((0..pixel_count)
        .map(|i| {
            let (f, d) = (fresnel[i], distant[i]);
            let l = local.as_ref().map_or([0.0; 4], |l| l[i]);
            let base = diffuse.as_ref().map_or([0.0; 4], |v| v[i]);
            let c = |k: usize| base[k] + f[k] * (l[k] + (1.0 - l[3]) * d[k]);
            [c(0), c(1), c(2), 1.0]
        })
        .collect())
}
