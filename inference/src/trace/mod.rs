//! The gold-standard CPU tracer: segmented layers per object, per viewpoint, as float EXR.
//!
//! A distribution ray tracer (see [`shading`]) over one obvhs BVH, parallel over 16×16
//! tiles with rayon, deterministic: sample `s` of pixel `p` draws from its own random
//! stream `(seed, p, s)`, and tiles are summed in a fixed order ([`film`]), so the same
//! scene, view, settings and seed give bit-identical layers at any thread count.
//!
//! # Layers (thesis ch. 3, PEM paper §4)
//!
//! Each pixel takes `spp` stratified samples; every sample's camera ray has one first-hit
//! object (or none). All sums below are filtered with the same Gaussian (σ = ½ px,
//! radius 1.5 px) and `w` is the filter weight:
//!
//! - `beauty` (RGB) = Σ w·L / Σ w, L the full radiance of the camera ray.
//! - `<o>.mask` (Y) = Σ w·[first hit is o] / Σ w: filtered coverage. Every object has one.
//!   The layers below are divided by o's filtered coverage `Σ_o w` (sums over o's samples),
//!   so they hold o's own shading, unmixed with neighbours, up to its silhouette.
//! - `<o>.diffuse` (RGB), Lambertian objects only: Σ_o w·L / Σ_o w.
//! - reflective objects (mirror, glossy, glass), with `r` the reflected ray of the first hit
//!   (mirror direction, or a direction drawn from the glossy lobe):
//!   - `<o>.fresnel` (RGB) = Σ_o w·F / Σ_o w, F = `schlick_fresnel(f0, n·v)` at the hit
//!     (the runtime's formula; glass: F from `f0 = ((ior − 1)/(ior + 1))²`, grey).
//!   - `<o>.specular_distant` (RGB) = Σ_o w·L_D / Σ_o w, L_D the radiance along `r` with o
//!     transparent for that one segment: the reflected ray passes through the reflector.
//!     Where `r` does not hit o anyway this is the same number as L(r). No alpha.
//!   - `<o>.specular_local` (RGBA): A = Σ_o w·h / Σ_o w with h = [r's first hit is o],
//!     RGB = Σ_o w·h·L(r) / Σ_o w·h (straight, not premultiplied; 0 where A = 0).
//!   - `<o>.transmission` (RGB), glass only: Σ_o w·(1 − F)·L(t) / Σ_o w, t the refracted ray.
//!
//! Per sample the split is exact: `L = F·(h·L(r) + (1 − h)·L_D) + (1 − F)·L(t)` for a
//! reflector, `L = diffuse` for a Lambertian object. After filtering, the runtime's
//! recombination `diffuse + fresnel × (local over distant)` (+ transmission) reproduces
//! `beauty` over the object up to the correlation of the filtered factors (noise-level
//! inside the object, larger at silhouettes where coverage is partial).
//!
//! Emitters get a mask only; an object with an unknown material index gets a mask only.

pub mod bvh;
pub mod cache;
pub mod camera;
mod error;
pub mod film;
mod lattice;
pub mod layers;
pub(crate) mod optics;
pub mod output;
pub mod photons;
pub mod rng;
pub mod shading;
pub mod surface;
pub mod transport;

#[cfg(test)]
mod caustic_tests;
#[cfg(test)]
mod group_tests;
#[cfg(test)]
mod light_tests;
#[cfg(test)]
mod material_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod trace_mesh_tests;

use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;

pub use bvh::SceneBvh;
pub use camera::CameraRays;
pub use error::TraceError;
pub use layers::{Layer, LayerPlan};
pub use optics::phong_exponent;
pub use photons::PhotonMap;
pub use shading::Integrator;
pub use transport::{Caustics, Transport};

use crate::scene::{Material, Scene};
use rng::Rng;

/// Samples per pixel at the default quality (see the README for the time it takes).
pub const DEFAULT_SPP: u32 = 16;
/// Output size when none is given: the thesis's 640×480.
pub const DEFAULT_SIZE: (u32, u32) = (640, 480);
/// As the CLI (`parse_size`): the film needs ~4 · channels bytes per pixel twice over.
const MAX_SIZE: u32 = 8192;
const MAX_SPP: u32 = 1 << 16;
const MAX_PHOTONS: u32 = 1 << 26;
/// Photon kernel radii the lattice handles in metre-scale scenes (i32 lattice indices).
const PHOTON_RADIUS: std::ops::RangeInclusive<f32> = 1e-4..=100.0;

/// Everything besides scene and view that decides an image (plus how to run).
#[derive(Clone, Debug, PartialEq)]
pub struct TraceSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    pub transport: Transport,
    /// Worker threads; `None` = rayon's default (all cores). Does not change pixels.
    pub threads: Option<usize>,
    /// Draw an indicatif progress bar on stderr.
    pub progress: bool,
}

impl Default for TraceSettings {
    fn default() -> Self {
        TraceSettings {
            width: DEFAULT_SIZE.0,
            height: DEFAULT_SIZE.1,
            spp: DEFAULT_SPP,
            seed: 0,
            transport: Transport::default(),
            threads: None,
            progress: false,
        }
    }
}

/// A traced image: all layers plus what it cost.
#[derive(Clone, Debug)]
pub struct TraceImage {
    pub width: u32,
    pub height: u32,
    pub layers: Vec<Layer>,
    /// Camera, shadow, reflection, refraction and bounce rays traced.
    pub rays: u64,
    pub elapsed: Duration,
}

impl TraceImage {
    pub fn layer(&self, name: &str) -> Option<&Layer> {
        self.layers.iter().find(|l| l.name == name)
    }

    pub fn mrays_per_s(&self) -> f64 {
        let s = self.elapsed.as_secs_f64();
        if s > 0.0 {
            self.rays as f64 / s / 1e6
        } else {
            0.0
        }
    }
}

/// A validated scene with its BVH, ready to trace any number of views.
pub struct Tracer<'a> {
    scene: &'a Scene,
    bvh: SceneBvh,
    plan: LayerPlan,
    /// The last photon map and what it was built from (transport, seed):
    /// it does not depend on the view, so views with the same settings
    /// share it (`trace --all`, eval references, inference targets).
    photons: std::sync::Mutex<Option<SharedPhotons>>,
}

/// A photon map and the (transport, seed) it was built with.
type SharedPhotons = ((Transport, u64), std::sync::Arc<PhotonMap>);

impl<'a> Tracer<'a> {
    /// Checks that the tracer can render `scene`, then builds its BVH.
    pub fn new(scene: &'a Scene) -> Result<Tracer<'a>, TraceError> {
        validate(scene)?;
        Ok(Tracer {
            scene,
            bvh: SceneBvh::build(scene),
            plan: LayerPlan::new(scene),
            photons: std::sync::Mutex::new(None),
        })
    }

    /// The scene this tracer renders.
    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    pub fn bvh_build_time(&self) -> Duration {
        self.bvh.build_time
    }

    pub fn triangle_count(&self) -> usize {
        self.bvh.triangle_count()
    }

    /// Names of the layers every image of this scene has, in file order.
    pub fn layer_names(&self) -> Vec<String> {
        self.plan.layer_names()
    }

    /// Eye of orbit sample `sample` (an error naming the range when out of it).
    pub fn sample_eye(&self, sample: u32) -> Result<Vec3, TraceError> {
        Ok(self.scene.orbit.sample_eye(sample)?)
    }

    /// Traces the view from `eye` (looking at the orbit centre, as the engine does).
    pub fn render(&self, eye: Vec3, settings: &TraceSettings) -> Result<TraceImage, TraceError> {
        settings.validate()?;
        if !eye.is_finite() {
            return Err(TraceError::Settings {
                field: "eye",
                message: format!("expected a finite position, got {eye}"),
            });
        }
        match settings.threads {
            None => Ok(self.render_here(eye, settings)),
            Some(threads) => rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|cause| TraceError::Threads { threads, cause })
                .map(|pool| pool.install(|| self.render_here(eye, settings))),
        }
    }

    fn render_here(&self, eye: Vec3, settings: &TraceSettings) -> TraceImage {
        let start = Instant::now();
        let (width, height) = (settings.width, settings.height);
        let camera = CameraRays::new(self.scene, eye, width, height);
        let integrator = Integrator::new(self.scene, &self.bvh, settings.transport);
        let (photons, photon_rays) = self.photon_map(&integrator, settings);
        let integrator = integrator.with_photons(photons.as_deref());
        let tiles = film::tiles(width, height);
        let progress = if settings.progress {
            indicatif::ProgressBar::new(tiles.len() as u64)
        } else {
            indicatif::ProgressBar::hidden()
        };
        progress.set_style(
            indicatif::ProgressStyle::with_template(
                "tracing [{bar:30}] {pos}/{len} tiles {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        let buffers: Vec<(film::TileBuffer, u64)> = tiles
            .par_iter()
            .map(|&tile| {
                let out = self.render_tile(tile, &camera, &integrator, settings);
                progress.inc(1);
                out
            })
            .collect();
        progress.finish_and_clear();

        let mut acc = vec![0.0f32; (width * height) as usize * self.plan.channels()];
        let mut rays = photon_rays;
        for (buffer, n) in &buffers {
            buffer.add_into(&mut acc, width, height);
            rays += n;
        }
        TraceImage {
            width,
            height,
            layers: self.plan.resolve(&acc, width, height),
            rays,
            elapsed: start.elapsed(),
        }
    }

    /// Runs `f` with the integrator (and caustic photon map) that `settings`
    /// trace with: for tracers of other quantities on the same scene (the
    /// glass targets), so they see exactly the radiance the layers see.
    pub fn with_integrator<R>(
        &self,
        settings: &TraceSettings,
        f: impl FnOnce(&Integrator, &SceneBvh) -> R,
    ) -> R {
        let integrator = Integrator::new(self.scene, &self.bvh, settings.transport);
        let (photons, _) = self.photon_map(&integrator, settings);
        let integrator = integrator.with_photons(photons.as_deref());
        f(&integrator, &self.bvh)
    }

    /// The photon map `settings` ask for, built on first use and shared by
    /// later views with the same transport and seed; with the photon rays
    /// this image paid for (0 when it reused the map).
    fn photon_map(
        &self,
        integrator: &Integrator,
        settings: &TraceSettings,
    ) -> (Option<std::sync::Arc<PhotonMap>>, u64) {
        let Caustics::Photons { photons, radius } = settings.transport.caustics else {
            return (None, 0);
        };
        let wanted = (settings.transport, settings.seed);
        let mut cached = self.photons.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((key, map)) = cached.as_ref()
            && *key == wanted
        {
            return (Some(map.clone()), 0);
        }
        let map = std::sync::Arc::new(PhotonMap::build(integrator, photons, radius, settings.seed));
        let rays = map.rays;
        *cached = Some((wanted, map.clone()));
        (Some(map), rays)
    }

    fn render_tile(
        &self,
        tile: film::Tile,
        camera: &CameraRays,
        integrator: &Integrator,
        settings: &TraceSettings,
    ) -> (film::TileBuffer, u64) {
        let mut buffer = film::TileBuffer::new(tile, self.plan.channels());
        let mut values = Vec::new();
        let mut rays = 0u64;
        for y in tile.y0..tile.y0 + tile.h {
            for x in tile.x0..tile.x0 + tile.w {
                let pixel = u64::from(y) * u64::from(settings.width) + u64::from(x);
                for s in 0..settings.spp {
                    let mut rng = Rng::new(settings.seed, pixel, s, 0);
                    let mut distant_rng = Rng::new(settings.seed, pixel, s, 1);
                    let (fx, fy) = film::sample_position(
                        x,
                        y,
                        s,
                        settings.spp,
                        rng.next_f32(),
                        rng.next_f32(),
                    );
                    let (origin, dir) = camera.ray(fx, fy);
                    let sample =
                        integrator.sample(origin, dir, &mut rng, &mut distant_rng, &mut rays);
                    self.plan.values(&sample, &mut values);
                    buffer.splat(fx, fy, &values);
                }
            }
        }
        (buffer, rays)
    }
}

impl TraceSettings {
    /// An error naming the first setting out of range (also checked by [`Tracer::render`]).
    pub fn validate(&self) -> Result<(), TraceError> {
        check_settings(self)
    }
}

fn check_settings(s: &TraceSettings) -> Result<(), TraceError> {
    if !(1..=MAX_SIZE).contains(&s.width) || !(1..=MAX_SIZE).contains(&s.height) {
        return Err(TraceError::Settings {
            field: "size",
            message: format!(
                "expected 1 to {MAX_SIZE} pixels each way, got {}x{}",
                s.width, s.height
            ),
        });
    }
    if !(1..=MAX_SPP).contains(&s.spp) {
        return Err(TraceError::Settings {
            field: "spp",
            message: format!("expected 1 to {MAX_SPP} samples per pixel, got {}", s.spp),
        });
    }
    if s.threads == Some(0) {
        return Err(TraceError::Settings {
            field: "threads",
            message: "expected at least 1".into(),
        });
    }
    if !s.transport.background.is_finite() || s.transport.background.min_element() < 0.0 {
        return Err(TraceError::Settings {
            field: "background",
            message: format!(
                "expected finite, non-negative radiance, got {}",
                s.transport.background
            ),
        });
    }
    if let Caustics::Photons { photons, radius } = s.transport.caustics {
        if !(1..=MAX_PHOTONS).contains(&photons) || !PHOTON_RADIUS.contains(&radius) {
            return Err(TraceError::Settings {
                field: "caustics",
                message: format!(
                    "expected 1 to {MAX_PHOTONS} photons and a radius of {} to {} m, got \
                     {photons} photons, radius {radius}",
                    PHOTON_RADIUS.start(),
                    PHOTON_RADIUS.end()
                ),
            });
        }
    }
    Ok(())
}

/// What the tracer needs beyond what the loader checks (scenes can also be built in code).
fn validate(scene: &Scene) -> Result<(), TraceError> {
    validate_lights(scene)?;
    validate_materials(scene)?;
    validate_objects(scene)
}

fn scene_error(scene: &Scene, field: String, message: String) -> TraceError {
    TraceError::Scene {
        scene: scene.origin.clone(),
        field,
        message,
    }
}

fn finite_nonneg(v: Vec3) -> bool {
    v.is_finite() && v.min_element() >= 0.0
}

fn validate_lights(scene: &Scene) -> Result<(), TraceError> {
    let bad = |field, message| scene_error(scene, field, message);
    for (i, l) in scene.lights.iter().enumerate() {
        let area = l.area();
        if !(area.is_finite() && area > 1e-12 && l.center.is_finite()) {
            return Err(bad(
                format!("lights[{i}] (\"{}\")", l.name),
                format!(
                    "light has zero area (edge_u {}, edge_v {})",
                    l.edge_u, l.edge_v
                ),
            ));
        }
        if !finite_nonneg(l.radiance) {
            return Err(bad(
                format!("lights[{i}].radiance"),
                format!("expected finite, non-negative values, got {}", l.radiance),
            ));
        }
    }
    Ok(())
}

fn validate_materials(scene: &Scene) -> Result<(), TraceError> {
    for (i, m) in scene.materials.iter().enumerate() {
        let name = scene.material_names.get(i).map_or("?", String::as_str);
        let field = format!("materials.{name}");
        if let Some(message) = material_problem(m, scene.textures.len()) {
            return Err(scene_error(scene, field, message));
        }
    }
    Ok(())
}

/// What is wrong with a material's parameters, if anything.
fn material_problem(m: &Material, n_textures: usize) -> Option<String> {
    match *m {
        Material::Diffuse { albedo, texture } => {
            if !finite_nonneg(albedo) {
                Some(format!(
                    "albedo must be finite and non-negative, got {albedo}"
                ))
            } else if texture.is_some_and(|t| t >= n_textures) {
                Some(format!("texture index {texture:?} out of range"))
            } else {
                None
            }
        }
        Material::Mirror { f0 } => (!finite_nonneg(f0)).then(|| format!("bad f0 {f0}")),
        Material::Glossy { f0, roughness } => {
            (!(finite_nonneg(f0) && roughness > 0.0 && roughness <= 1.0))
                .then(|| format!("f0 {f0}, roughness {roughness}: expected roughness in (0, 1]"))
        }
        Material::Glass { ior, absorption } => {
            (!(ior.is_finite() && ior >= 1.0 && finite_nonneg(absorption)))
                .then(|| format!("ior {ior}, absorption {absorption}: expected ior ≥ 1"))
        }
        Material::Emissive { radiance } => {
            (!finite_nonneg(radiance)).then(|| format!("bad radiance {radiance}"))
        }
    }
}

fn validate_objects(scene: &Scene) -> Result<(), TraceError> {
    let bad = |field, message| scene_error(scene, field, message);
    for (i, o) in scene.objects.iter().enumerate() {
        if o.material >= scene.materials.len() {
            return Err(bad(
                format!("objects[{i}] (\"{}\").material", o.name),
                format!(
                    "unknown material index {} (the scene has {})",
                    o.material,
                    scene.materials.len()
                ),
            ));
        }
        let m = o.traced_mesh();
        let n = m.positions.len();
        if m.indices.len() % 3 != 0 || m.indices.iter().any(|&ix| ix as usize >= n) {
            return Err(bad(
                format!("objects[{i}] (\"{}\").mesh", o.name),
                "indices must form triangles over existing vertices".into(),
            ));
        }
        if m.positions.iter().any(|p| !p.is_finite()) {
            return Err(bad(
                format!("objects[{i}] (\"{}\").mesh", o.name),
                "non-finite vertex position".into(),
            ));
        }
    }
    Ok(())
}
