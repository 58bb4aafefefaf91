//! What the shell maps are inferred against (thesis §6.3.3): per pixel, the
//! radiance along the greedy paths' exit rays, one image per term and
//! shell, and a confidence per pixel and term.
//!
//! Every film sample whose camera ray first meets the lens follows the two
//! greedy paths from that hit; each exit ray is continued through the
//! objects of other shells to the first hit on this shell's objects (so a
//! far layer is known behind a near one), shaded by the tracer's own
//! integrator. A pixel's term image is premultiplied RGBA: RGB the mean
//! over the samples whose path exits of `radiance · [hit this shell]`, A
//! the fraction that hit it (1 on the room's box). Confidence is
//! `(1 − min(θ_m², θ_c²)/θ_c²) · exiting/spp`, θ_m the widest angle between
//! the pixel's exit rays, θ_c = 5°.

use glam::Vec3;
use rayon::prelude::*;

use super::lens::Lens;
use super::path::{Path, angle_deg, two_paths};
use super::shells::ShellSet;
use crate::trace::camera::CameraRays;
use crate::trace::rng::Rng;
use crate::trace::{Integrator, SceneBvh, TraceSettings, Tracer, film};

/// θ_c: exit rays this far apart in one pixel leave it no confidence.
pub const CONFIDENCE_ANGLE_DEG: f32 = 5.0;

/// One term's images.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TermImages {
    /// Per shell, premultiplied RGBA per pixel (row-major from the top).
    pub shells: Vec<Vec<[f32; 4]>>,
    pub confidence: Vec<f32>,
    /// Per pixel, the term's `F·G` per channel, the mean over the samples
    /// whose first hit is the lens (0 where its path never leaves): what
    /// the pixel's shell radiance is multiplied by in the frame.
    pub weight: Vec<[f32; 3]>,
}

/// Both terms' images of one view.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GlassTargets {
    pub width: u32,
    pub height: u32,
    pub t: TermImages,
    pub r: TermImages,
    /// Fraction of each pixel's samples whose first hit is the lens.
    pub coverage: Vec<f32>,
    pub rays: u64,
}

/// Traces the targets of the view from `eye` at `settings` (size, spp,
/// seed, transport; the tracer's photon map is shared).
pub fn trace_targets(
    tracer: &Tracer,
    lens: &Lens,
    shells: &ShellSet,
    eye: Vec3,
    settings: &TraceSettings,
) -> GlassTargets {
    let (width, height) = (settings.width, settings.height);
    let camera = CameraRays::new(tracer.scene(), eye, width, height);
    let rows: Vec<(Vec<PixelResult>, u64)> = tracer.with_integrator(settings, |integrator, bvh| {
        let view = View {
            integrator,
            bvh,
            lens,
            shells,
            camera: &camera,
            settings,
        };
        (0..height)
            .into_par_iter()
            .map(|y| {
                let mut rays = 0;
                let row = (0..width).map(|x| view.pixel(x, y, &mut rays)).collect();
                (row, rays)
            })
            .collect()
    });
    let n = shells.shells.len();
    let mut out = GlassTargets {
        width,
        height,
        t: TermImages {
            shells: vec![Vec::with_capacity((width * height) as usize); n],
            confidence: Vec::new(),
            weight: Vec::new(),
        },
        coverage: Vec::new(),
        ..GlassTargets::default()
    };
    out.r = out.t.clone();
    for (row, rays) in rows {
        out.rays += rays;
        for p in row {
            out.coverage.push(p.coverage);
            for (images, term) in [(&mut out.t, &p.t), (&mut out.r, &p.r)] {
                images.confidence.push(term.confidence);
                images.weight.push(term.weight);
                for (i, image) in images.shells.iter_mut().enumerate() {
                    image.push(term.shells.get(i).copied().unwrap_or([0.0; 4]));
                }
            }
        }
    }
    out
}

struct View<'a> {
    integrator: &'a Integrator<'a>,
    bvh: &'a SceneBvh,
    lens: &'a Lens,
    shells: &'a ShellSet,
    camera: &'a CameraRays,
    settings: &'a TraceSettings,
}

#[derive(Default)]
struct PixelResult {
    coverage: f32,
    t: TermPixel,
    r: TermPixel,
}

#[derive(Default)]
struct TermPixel {
    shells: Vec<[f32; 4]>,
    confidence: f32,
    weight: [f32; 3],
}

/// One term's sums over a pixel's samples.
struct TermSums {
    /// Per shell: Σ radiance·[hit], Σ [hit].
    shells: Vec<([f64; 3], u32)>,
    dirs: Vec<Vec3>,
    /// Σ F·G over the samples on the lens.
    weight: Vec3,
}

impl View<'_> {
    fn pixel(&self, x: u32, y: u32, rays: &mut u64) -> PixelResult {
        let s = self.settings;
        let pixel = u64::from(y) * u64::from(s.width) + u64::from(x);
        let n = self.shells.shells.len();
        let mut sums = [0, 1].map(|_| TermSums {
            shells: vec![([0.0; 3], 0); n],
            dirs: Vec::new(),
            weight: Vec3::ZERO,
        });
        let mut on_lens = 0u32;
        for k in 0..s.spp {
            let mut rng = Rng::new(s.seed, pixel, k, 0);
            let (fx, fy) = film::sample_position(x, y, k, s.spp, rng.next_f32(), rng.next_f32());
            let (origin, dir) = self.camera.ray(fx, fy);
            *rays += 1;
            let Some(hit) = self.bvh.closest(origin, dir, 0.0, f32::INFINITY, None) else {
                continue;
            };
            if hit.prim.object != self.lens.object {
                continue;
            }
            on_lens += 1;
            let surface = self.lens.surface(&hit, dir);
            let paths = two_paths(self.lens, &surface, dir, None);
            *rays +=
                u64::from(paths.t.topology.interfaces) + u64::from(paths.r.topology.interfaces);
            for (term, path) in sums.iter_mut().zip([&paths.t, &paths.r]) {
                term.weight += path.weight;
                if path.exited() {
                    self.exit(path, term, &mut rng, rays);
                }
            }
        }
        let [t, r] = sums.map(|term| finish(term, s.spp, on_lens));
        PixelResult {
            coverage: on_lens as f32 / s.spp.max(1) as f32,
            t,
            r,
        }
    }

    /// The exit ray of `path` into every shell: its first hit among the
    /// shell's objects, shaded.
    fn exit(&self, path: &Path, term: &mut TermSums, rng: &mut Rng, rays: &mut u64) {
        term.dirs.push(path.dir);
        let lens = self.lens.object;
        let bounces = u32::from(path.topology.interfaces);
        for (shell, sum) in self.shells.shells.iter().zip(term.shells.iter_mut()) {
            *rays += 1;
            let keep = |o: u32| o != lens && shell.objects.contains(&o);
            let Some(hit) = self
                .bvh
                .closest_where(path.origin, path.dir, 0.0, f32::INFINITY, keep)
            else {
                continue;
            };
            let l = self
                .integrator
                .radiance_at(hit, path.dir, bounces, rng, rays);
            for c in 0..3 {
                sum.0[c] += f64::from(l[c]);
            }
            sum.1 += 1;
        }
    }
}

/// A pixel's term images, confidence and weight from its sums over `spp`
/// samples, `on_lens` of which hit the lens first.
fn finish(term: TermSums, spp: u32, on_lens: u32) -> TermPixel {
    let weight = (term.weight / on_lens.max(1) as f32).to_array();
    let exiting = term.dirs.len();
    if exiting == 0 {
        return TermPixel {
            shells: vec![[0.0; 4]; term.shells.len()],
            confidence: 0.0,
            weight,
        };
    }
    let shells = term
        .shells
        .iter()
        .map(|(rgb, hits)| {
            let n = exiting as f64;
            [
                (rgb[0] / n) as f32,
                (rgb[1] / n) as f32,
                (rgb[2] / n) as f32,
                (f64::from(*hits) / n) as f32,
            ]
        })
        .collect();
    TermPixel {
        shells,
        confidence: confidence(&term.dirs) * exiting as f32 / spp.max(1) as f32,
        weight,
    }
}

/// `1 − min(θ_m², θ_c²)/θ_c²` for the widest angle θ_m between `dirs`.
pub fn confidence(dirs: &[Vec3]) -> f32 {
    let mut widest = 0.0f32;
    for (i, a) in dirs.iter().enumerate() {
        for b in &dirs[i + 1..] {
            widest = widest.max(angle_deg(*a, *b));
        }
    }
    let c2 = CONFIDENCE_ANGLE_DEG * CONFIDENCE_ANGLE_DEG;
    1.0 - (widest * widest).min(c2) / c2
}
