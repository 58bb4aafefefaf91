//! Targets from the tracer: a traced layer as RGBA pixels, and a
//! reflector's composite appearance.

use anyhow::{Context, Result, bail};
use inference::trace::output;

/// `name`'s pixels as RGBA (premultiplied by A when `premultiply`).
pub fn target_pixels(
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
    let a = get("A");
    // Every channel, not only R: a file may hold channels of other sizes.
    for (c, v) in [("R", r), ("G", g), ("B", b)]
        .into_iter()
        .chain(a.map(|a| ("A", a)))
    {
        if v.len() != pixel_count {
            bail!(
                "layer {name:?} channel {c}: {} pixels, the probe renders have {pixel_count} (trace at the same --size)",
                v.len()
            );
        }
    }
    Ok((0..pixel_count)
        .map(|i| {
            let alpha = a.map_or(1.0, |a| a[i]);
            let k = if premultiply { alpha } else { 1.0 };
            [r[i] * k, g[i] * k, b[i] * k, alpha]
        })
        .collect())
}

/// The reflector's whole specular appearance before Fresnel, `local over
/// distant` = `rgb_L · α_L + (1 − α_L) · rgb_D`, opaque: the target of a
/// single EM standing for both layers. The traced distant and local layers
/// carry no Fresnel (the tracer keeps it in its own layer and the probe
/// renders read the Fresnel LUT at 1), so the runtime shades this map as it
/// shades the distant layer, `fresnel × map`, and at the sample view that
/// reproduces `fresnel × (local over distant)`, the layered PEM's specular
/// term.
pub(crate) fn specular_pixels(
    layers: &[output::ExrLayer],
    object: &str,
    pixel_count: usize,
) -> Result<Vec<[f32; 4]>> {
    Ok(local_over_distant(layers, object, pixel_count, true)?
        .into_iter()
        .map(|[r, g, b]| [r, g, b, 1.0])
        .collect())
}

/// `local over distant` per pixel: `rgb_L·α_L + (1 − α_L)·rgb_D`, the
/// distant layer alone where the object has no local layer (unless
/// `require_local`).
fn local_over_distant(
    layers: &[output::ExrLayer],
    object: &str,
    pixel_count: usize,
    require_local: bool,
) -> Result<Vec<[f32; 3]>> {
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
    );
    let local = if require_local {
        Some(local?)
    } else {
        local.ok()
    };
    Ok(distant
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let l = local.as_ref().map_or([0.0; 4], |l| l[i]);
            std::array::from_fn(|k| l[k] + (1.0 - l[3]) * d[k])
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
    let specular = local_over_distant(layers, object, pixel_count, false)?;
    let diffuse = target_pixels(layers, &format!("{object}.diffuse"), false, pixel_count).ok();
    Ok((0..pixel_count)
        .map(|i| {
            let base = diffuse.as_ref().map_or([0.0; 4], |v| v[i]);
            let c = |k: usize| base[k] + fresnel[i][k] * specular[i][k];
            [c(0), c(1), c(2), 1.0]
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layer(name: &str, channels: &[(&str, [f32; 2])]) -> output::ExrLayer {
        (
            name.to_string(),
            channels
                .iter()
                .map(|(c, v)| (c.to_string(), v.to_vec()))
                .collect(),
        )
    }

    #[test]
    fn the_sphere_target_is_local_over_distant_and_fresnel_makes_it_the_composite() {
        let layers = vec![
            layer(
                "pot.fresnel",
                &[("R", [0.5, 1.0]), ("G", [0.6, 1.0]), ("B", [0.7, 1.0])],
            ),
            layer(
                "pot.specular_distant",
                &[("R", [1.0, 2.0]), ("G", [2.0, 2.0]), ("B", [3.0, 2.0])],
            ),
            // Straight RGB with coverage alpha, as the tracer writes it.
            layer(
                "pot.specular_local",
                &[
                    ("R", [4.0, 0.0]),
                    ("G", [4.0, 0.0]),
                    ("B", [4.0, 0.0]),
                    ("A", [0.25, 0.0]),
                ],
            ),
        ];
        let sphere = specular_pixels(&layers, "pot", 2).expect("sphere target");
        // 0.25 · 4 + 0.75 · distant; no local at the second pixel.
        assert_eq!(sphere, [[1.75, 2.5, 3.25, 1.0], [2.0, 2.0, 2.0, 1.0]]);
        let composite = composite_pixels(&layers, "pot", 2).expect("composite");
        let fresnel = target_pixels(&layers, "pot.fresnel", false, 2).expect("fresnel");
        for ((s, c), f) in sphere.iter().zip(&composite).zip(&fresnel) {
            for k in 0..3 {
                assert!((f[k] * s[k] - c[k]).abs() < 1e-6, "{s:?} {c:?} {f:?}");
            }
        }
        let err = specular_pixels(&layers[..2], "pot", 2).expect_err("no local layer");
        assert!(format!("{err:#}").contains("pot.specular_local"), "{err:#}");
        assert!(specular_pixels(&layers, "pot", 3).is_err(), "pixel count");
    }

    #[test]
    fn a_channel_shorter_than_the_image_is_an_error_not_a_panic() {
        for short in ["G", "B", "A"] {
            let channels: Vec<(String, Vec<f32>)> = ["R", "G", "B", "A"]
                .iter()
                .map(|c| (c.to_string(), vec![1.0; if *c == short { 1 } else { 2 }]))
                .collect();
            let layers = vec![("pot.specular_local".to_string(), channels)];
            let err =
                target_pixels(&layers, "pot.specular_local", true, 2).expect_err("short channel");
            assert!(
                format!("{err:#}").contains(&format!("channel {short}")),
                "{err:#}"
            );
        }
    }
}
