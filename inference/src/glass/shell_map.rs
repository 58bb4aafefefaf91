//! Shell maps traced (not rasterised): per cube texel, the tracer's own
//! radiance of the first surface seen from the shell origin in that
//! direction, the lens (and, for a layer, the nearer layers' objects)
//! transparent — what an exit ray meets there, caustics and indirect light
//! included, so hybrid frames and traced frames see one room. A layer that
//! is not the outermost holds premultiplied RGBA: alpha is the fraction of
//! the texel's rays whose first visible hit is one of its own objects.
//! Vulkan cube order and orientation (`solve::seams::cube_dir`),
//! face-major, rows from the top; then a box-filtered MIP chain.

use glam::Vec3;
use rayon::prelude::*;

use crate::solve::seams::cube_dir;
use crate::trace::film;
use crate::trace::rng::Rng;
use crate::trace::{TraceSettings, Tracer};

/// Specular bounces a room hit counts as having behind it: the typical
/// path in through the glass and out again.
const SPECULAR_BEFORE: u32 = 2;

/// Level 0 of the shell map of `size`² texels per face at `origin`, the
/// lens (`skip`) transparent; `settings` give spp, seed and transport.
pub fn trace_shell_map(
    tracer: &Tracer,
    skip: u32,
    origin: Vec3,
    size: u32,
    settings: &TraceSettings,
) -> Vec<[f32; 3]> {
    let layer = LayerObjects {
        hidden: &[skip],
        own: None,
    };
    trace_layer_map(tracer, &layer, origin, size, settings)
        .into_iter()
        .map(|[r, g, b, _]| [r, g, b])
        .collect()
}

/// Which objects a traced layer sees.
#[derive(Clone, Copy, Debug)]
pub struct LayerObjects<'a> {
    /// Transparent to the rays from the origin (the lens, nearer layers).
    pub hidden: &'a [u32],
    /// The layer's own objects (None: whatever is seen, alpha 1 — the
    /// outermost layer).
    pub own: Option<&'a [u32]>,
}

/// Level 0 of a layer's map of `size`² texels per face at `origin`:
/// premultiplied RGBA, alpha the fraction of rays whose first hit (past
/// `layer.hidden`) is the layer's own.
pub fn trace_layer_map(
    tracer: &Tracer,
    layer: &LayerObjects,
    origin: Vec3,
    size: u32,
    settings: &TraceSettings,
) -> Vec<[f32; 4]> {
    let spp = settings.spp.max(1);
    tracer.with_integrator(settings, |integrator, bvh| {
        (0..6 * size)
            .into_par_iter()
            .flat_map_iter(|row| {
                let (face, y) = (row / size, row % size);
                (0..size).map(move |x| {
                    let pixel = u64::from(row) * u64::from(size) + u64::from(x);
                    let mut sum = Vec3::ZERO;
                    let mut covered = 0u32;
                    let mut rays = 0u64;
                    for k in 0..spp {
                        let mut rng = Rng::new(settings.seed, pixel, k, 1);
                        let (fx, fy) =
                            film::sample_position(x, y, k, spp, rng.next_f32(), rng.next_f32());
                        let s = 2.0 * fx / size as f32 - 1.0;
                        let t = 2.0 * fy / size as f32 - 1.0;
                        let d = cube_dir(face, f64::from(s), f64::from(t));
                        let dir = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32).normalize();
                        let keep = |o: u32| !layer.hidden.contains(&o);
                        let hit = bvh.closest_where(origin, dir, 0.0, f32::INFINITY, keep);
                        let Some(hit) = hit
                            .filter(|h| layer.own.is_none_or(|own| own.contains(&h.prim.object)))
                        else {
                            continue;
                        };
                        covered += 1;
                        sum +=
                            integrator.radiance_at(hit, dir, SPECULAR_BEFORE, &mut rng, &mut rays);
                    }
                    let l = sum / spp as f32;
                    let alpha = match layer.own {
                        Some(_) => covered as f32 / spp as f32,
                        None => 1.0,
                    };
                    if l.is_finite() {
                        [l.x, l.y, l.z, alpha]
                    } else {
                        [0.0, 0.0, 0.0, alpha]
                    }
                })
            })
            .collect()
    })
}

/// Every MIP level of a cube map whose level 0 is `level0` (`size`² per
/// face), level-major, each texel the mean of its four parents (for a
/// premultiplied layer, the filter the device applies).
pub fn mip_chain<const N: usize>(level0: Vec<[f32; N]>, size: u32) -> Vec<Vec<[f32; N]>> {
    let mut levels = vec![level0];
    let mut n = size as usize;
    while n > 1 {
        let half = n / 2;
        let above = &levels[levels.len() - 1];
        let mut next = Vec::with_capacity(6 * half * half);
        for face in 0..6 {
            for y in 0..half {
                for x in 0..half {
                    let at =
                        |dx: usize, dy: usize| above[face * n * n + (2 * y + dy) * n + 2 * x + dx];
                    let mut s = [0.0f32; N];
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let p = at(dx, dy);
                        for c in 0..N {
                            s[c] += 0.25 * p[c];
                        }
                    }
                    next.push(s);
                }
            }
        }
        levels.push(next);
        n = half;
    }
    levels
}
