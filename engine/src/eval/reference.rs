//! The gold standard of any view on or off the orbit: traced on demand,
//! cached on disk, read back as the frames and the reflector mask that
//! [`super::metrics`] compares rendered frames with.
//!
//! A view is an azimuth on the scene's orbit and an elevation off it
//! ([`inference::scene::Orbit::eye`]), so views between orbit samples and
//! above the orbit are as easy to ask for as the samples themselves.
//!
//! Cache: `<dir>/view_az±A_el±E_WxH_Nspp.{exr,png,key}`, the tracer's usual
//! files (all layers as float EXR, a tone-mapped PNG for people), written
//! atomically; the `.exr.key` record holds [`inference::trace::cache::image_key`]
//! of scene, eye and settings, so a second request with the same inputs reads
//! the EXR instead of tracing, and a changed scene, seed or transport (or a
//! damaged file) re-traces.

use crate::compile::infer::targets::{composite_pixels, target_pixels};
use crate::compile::trace::cached_or_traced;
use anyhow::{Context, Result, bail};
use glam::Vec3;
use inference::scene::{Material, Scene};
use inference::trace::{TraceSettings, Tracer, cache, output};
use std::cell::OnceCell;
use std::path::{Path, PathBuf};

/// Coverage from which a pixel belongs to the reflector in
/// [`ReferenceImage::mask`]: ½ is where the traced silhouette crosses the
/// pixel centre, the rasteriser's own coverage rule.
pub const MASK_COVERAGE: f32 = 0.5;

/// A viewpoint: azimuth on the orbit and elevation off it, in degrees, as
/// [`inference::scene::Orbit::eye`] takes them (orbit sample `k` is
/// `View::on_orbit(orbit.angle_deg(k))`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub azimuth_deg: f32,
    pub elevation_deg: f32,
}

impl View {
    pub fn new(azimuth_deg: f32, elevation_deg: f32) -> View {
        // + 0.0 turns −0 into +0: one name and one eye for "zero".
        View {
            azimuth_deg: azimuth_deg + 0.0,
            elevation_deg: elevation_deg + 0.0,
        }
    }

    /// On the orbit itself (elevation 0).
    pub fn on_orbit(azimuth_deg: f32) -> View {
        View::new(azimuth_deg, 0.0)
    }

    /// The eye position in `scene`.
    pub fn eye(&self, scene: &Scene) -> Vec3 {
        scene
            .orbit
            .eye(self.azimuth_deg + 0.0, self.elevation_deg + 0.0)
    }
}

/// The seed of the eval's references: no compile traces with it (the maps'
/// traces use 0, the glass shell solves' frames 1), so every reference is
/// held out, the views on samples too.
pub const REFERENCE_SEED: u64 = 2;

/// How a reference of `size` is traced at `spp` samples per pixel: with
/// [`REFERENCE_SEED`], showing progress (eval's views and `--score`'s alike).
pub fn reference_settings((width, height): (u32, u32), spp: u32) -> TraceSettings {
    TraceSettings {
        width,
        height,
        spp,
        seed: REFERENCE_SEED,
        progress: true,
        ..TraceSettings::default()
    }
}
const _: () = assert!(
    REFERENCE_SEED != crate::compile::glass_shells::views::SOLVE_FRAME_SEED && REFERENCE_SEED != 0
);

/// The traced reference of one view, seen through one reflector. Every
/// per-pixel vector has `width × height` entries, row-major from the top
/// (the order of `Renderer::pixels()`).
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    pub view: View,
    pub eye: Vec3,
    pub width: u32,
    pub height: u32,
    /// The reflector the mask and composite are of.
    pub object: String,
    /// The full traced frame (`beauty` layer), linear RGB, alpha 1.
    pub beauty: Vec<[f32; 4]>,
    /// The reflector's filtered coverage (`<object>.mask` layer), 0 to 1.
    pub coverage: Vec<f32>,
    /// `coverage ≥ MASK_COVERAGE`: the pixels that show the reflector.
    pub mask: Vec<bool>,
    /// The reflector alone from its layers, as the runtime composites it:
    /// `fresnel × (local over distant)`, alpha 1; meaningful where `coverage`
    /// is > 0 (elsewhere the layers are 0). Glass: no transmission term.
    pub composite: Vec<[f32; 4]>,
    /// Cache key of the traced image.
    pub key: inference::key::Key,
    /// The EXR all this was read from.
    pub exr: PathBuf,
    /// True when this call traced the view, false when it came from the cache.
    pub traced: bool,
}

impl ReferenceImage {
    /// Pixels whose coverage is at least `min_coverage`: 1.0 keeps the
    /// reflector's interior only, leaving out its anti-aliased silhouette.
    pub fn mask_where(&self, min_coverage: f32) -> Vec<bool> {
        self.coverage.iter().map(|&c| c >= min_coverage).collect()
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// References of one scene at one size and setting, cached under one folder.
/// The tracer (and its BVH) is built on the first view that needs tracing.
pub struct References<'a> {
    scene: &'a Scene,
    scene_key: inference::key::Key,
    dir: PathBuf,
    settings: TraceSettings,
    tracer: OnceCell<Tracer<'a>>,
}

impl<'a> References<'a> {
    /// Checks `settings` (size, spp, …) before anything is traced or written.
    pub fn new(scene: &'a Scene, dir: &Path, settings: TraceSettings) -> Result<References<'a>> {
        settings
            .validate()
            .context("trace settings of the eval references")?;
        Ok(References {
            scene,
            scene_key: cache::scene_key(scene),
            dir: dir.to_owned(),
            settings,
            tracer: OnceCell::new(),
        })
    }

    pub fn settings(&self) -> &TraceSettings {
        &self.settings
    }

    /// Where `view`'s files go, without suffix.
    pub fn stem(&self, view: View) -> PathBuf {
        let s = &self.settings;
        self.dir.join(format!(
            "view_az{:+.3}_el{:+.3}_{}x{}_{}spp",
            view.azimuth_deg + 0.0,
            view.elevation_deg + 0.0,
            s.width,
            s.height,
            s.spp
        ))
    }

    /// The reference of `view` through reflector `object` (a mirror, glossy
    /// or glass object of the scene), tracing it first unless the cache
    /// holds it with the same inputs.
    pub fn get(&self, view: View, object: &str) -> Result<ReferenceImage> {
        self.get_all(view, &[object])
    }

    /// The reference of `view` through all of `objects` at once (a
    /// teapot's lid and body), read from one traced image: their coverages
    /// and composites summed, so the mask holds every pixel a viewer sees
    /// as one of them; `object` names them joined by `+`.
    pub fn get_all<S: AsRef<str>>(&self, view: View, objects: &[S]) -> Result<ReferenceImage> {
        let objects: Vec<&str> = objects.iter().map(AsRef::as_ref).collect();
        if objects.is_empty() {
            bail!("no reflector to score (bug: an empty list)");
        }
        for object in &objects {
            self.check_reflector(object)?;
        }
        let eye = view.eye(self.scene);
        let stem = self.stem(view);
        let key = cache::image_key(&self.scene_key, eye, &self.settings);
        let (layers, traced) = cached_or_traced(&stem, &key, || {
            Ok(self.tracer()?.render(eye, &self.settings)?)
        })?;
        let exr = output::with_suffix(&stem, ".exr");
        let (width, height) = (self.settings.width, self.settings.height);
        let n = width as usize * height as usize;
        let object = objects.join("+");
        let read = || -> Result<_> {
            let beauty = target_pixels(&layers, "beauty", false, n)?;
            let (mut coverage, mut composite) = (vec![0.0; n], vec![[0.0; 4]; n]);
            for part in &objects {
                let c = channel(&layers, &format!("{part}.mask"), "Y", n)?;
                coverage.iter_mut().zip(c).for_each(|(a, b)| *a += b);
                let rgba = composite_pixels(&layers, part, n)?;
                for (a, b) in composite.iter_mut().zip(rgba) {
                    *a = [a[0] + b[0], a[1] + b[1], a[2] + b[2], 1.0];
                }
            }
            Ok((beauty, coverage, composite))
        };
        let (beauty, coverage, composite) = read().with_context(|| {
            format!(
                "{}: expected the traced layers of {object:?} at {width}x{height}",
                exr.display()
            )
        })?;
        Ok(ReferenceImage {
            view,
            eye,
            width,
            height,
            object,
            mask: coverage.iter().map(|&c| c >= MASK_COVERAGE).collect(),
            beauty,
            coverage,
            composite,
            key,
            exr,
            traced,
        })
    }

    fn tracer(&self) -> Result<&Tracer<'a>> {
        if self.tracer.get().is_none() {
            let tracer = Tracer::new(self.scene)?;
            let _ = self.tracer.set(tracer);
        }
        self.tracer
            .get()
            .context("the tracer was built but is not there (bug)")
    }

    fn check_reflector(&self, object: &str) -> Result<()> {
        let is_reflector = |material: usize| {
            matches!(
                self.scene.materials.get(material),
                Some(Material::Mirror { .. } | Material::Glossy { .. } | Material::Glass { .. })
            )
        };
        if self
            .scene
            .object(object)
            .is_some_and(|o| is_reflector(o.material))
        {
            return Ok(());
        }
        let reflectors: Vec<&str> = self
            .scene
            .objects
            .iter()
            .filter(|o| is_reflector(o.material))
            .map(|o| o.name.as_str())
            .collect();
        bail!(
            "scene {:?}: {object:?} is not a reflecting object; expected one of {reflectors:?}",
            self.scene.name
        )
    }
}

/// Channel `channel` of layer `layer`, checked to hold `n` pixels.
fn channel(layers: &[output::ExrLayer], layer: &str, channel: &str, n: usize) -> Result<Vec<f32>> {
    let (_, channels) = layers
        .iter()
        .find(|(name, _)| name == layer)
        .with_context(|| format!("traced image has no layer {layer:?}"))?;
    let (_, values) = channels
        .iter()
        .find(|(name, _)| name == channel)
        .with_context(|| format!("layer {layer:?}: expected a channel {channel}"))?;
    if values.len() != n {
        bail!("layer {layer:?}: {} pixels, expected {n}", values.len());
    }
    Ok(values.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: u32 = 32;
    const H: u32 = 24;

    fn tiny() -> TraceSettings {
        TraceSettings {
            width: W,
            height: H,
            spp: 1,
            threads: Some(1),
            ..TraceSettings::default()
        }
    }

    fn teapot(_: &Path) -> Result<Scene> {
        Ok(Scene::load("teapot")?)
    }

    fn modified(path: &Path) -> Result<std::time::SystemTime> {
        Ok(std::fs::metadata(path)?.modified()?)
    }

    #[test]
    fn traces_once_then_reads_the_cache() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let scene = teapot(dir.path())?;
        let refs = References::new(&scene, &dir.path().join("refs"), tiny())?;
        let view = View::new(12.5, 10.0);
        let first = refs.get(view, "teapot")?;
        assert!(first.traced);
        assert_eq!(first.beauty.len(), (W * H) as usize);
        assert_eq!(first.mask.len(), (W * H) as usize);
        assert_eq!(first.composite.len(), (W * H) as usize);
        assert!(first.exr.is_file());
        assert!(output::with_suffix(&refs.stem(view), ".png").is_file());
        let when = modified(&first.exr)?;

        let second = refs.get(view, "teapot")?;
        assert!(!second.traced, "same inputs must not trace again");
        assert_eq!(modified(&second.exr)?, when);
        assert_eq!(second.beauty, first.beauty);
        assert_eq!(second.mask, first.mask);
        assert_eq!(second.key, first.key);
        // A fresh References over the same folder (a new run) reads it too.
        let again = References::new(&scene, &dir.path().join("refs"), tiny())?;
        assert!(!again.get(view, "teapot")?.traced);
        Ok(())
    }

    /// The default teapot's lid and body score as one reflector: the
    /// pixels of either, as many as the whole teapot covers.
    #[test]
    fn lid_and_body_score_together_as_the_whole_teapot() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let view = View::new(12.5, 20.0);
        let split = Scene::load("teapot_split")?;
        let refs = References::new(&split, &dir.path().join("split"), tiny())?;
        let parts = ["body".to_owned(), "lid".to_owned()];
        let both = refs.get_all(view, &parts)?;
        let count = |m: &[bool]| m.iter().filter(|&&b| b).count();
        let whole = teapot(dir.path())?;
        let whole = References::new(&whole, &dir.path().join("whole"), tiny())?;
        let whole = count(&whole.get(view, "teapot")?.mask);
        for part in &parts {
            let mask = refs.get(view, part)?.mask;
            assert!(count(&mask) > 0, "{part} covers no pixel");
            assert!(
                mask.iter().zip(&both.mask).all(|(&p, &b)| !p || b),
                "{part}"
            );
        }
        let (n, body) = (count(&both.mask), count(&refs.get(view, "body")?.mask));
        assert!(
            n > body && n.abs_diff(whole) <= 1 + whole / 50,
            "{n} vs {whole}"
        );
        assert_eq!(both.object, "body+lid");
        Ok(())
    }

    #[test]
    fn changed_inputs_trace_again() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let scene = teapot(dir.path())?;
        let refs_dir = dir.path().join("refs");
        let a = References::new(&scene, &refs_dir, tiny())?.get(View::on_orbit(30.0), "teapot")?;
        let other_seed = TraceSettings { seed: 7, ..tiny() };
        let refs = References::new(&scene, &refs_dir, other_seed)?;
        let b = refs.get(View::on_orbit(30.0), "teapot")?;
        assert!(b.traced, "another seed is another image");
        assert_ne!(a.key, b.key);
        // Another view is another file, and another picture.
        let c = refs.get(View::new(30.0, 25.0), "teapot")?;
        assert!(c.traced);
        assert_ne!(c.exr, b.exr);
        assert_ne!(c.beauty, b.beauty);
        Ok(())
    }

    #[test]
    fn mask_and_composite_show_the_teapot() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let scene = teapot(dir.path())?;
        let refs = References::new(&scene, dir.path(), tiny())?;
        let r = refs.get(View::on_orbit(20.0), "teapot")?;
        let masked = r.mask.iter().filter(|&&m| m).count();
        assert!(
            masked > 30 && masked < r.pixel_count() / 2,
            "{masked} teapot pixels"
        );
        // The orbit looks at the teapot: the centre shows it, the corners do not.
        let at = |x: u32, y: u32| (y * W + x) as usize;
        assert!(r.mask[at(W / 2, H / 2)]);
        for (x, y) in [(0, 0), (W - 1, 0), (0, H - 1), (W - 1, H - 1)] {
            assert!(!r.mask[at(x, y)]);
        }
        // Row-major from the top: the floor fills the bottom row, not the top one.
        let layers = output::read_exr(&r.exr)?;
        let floor = channel(&layers, "floor.mask", "Y", r.pixel_count())?;
        assert!((0..W).all(|x| floor[at(x, H - 1)] > 0.99));
        assert!((0..W).all(|x| floor[at(x, 0)] < 0.01));
        // The interior mask is a subset of the ½-coverage one.
        let interior = r.mask_where(1.0);
        assert!(interior.iter().zip(&r.mask).all(|(i, m)| !i || *m));
        // Inside, the reflector's own composite reproduces the traced frame
        // (up to the filtered factors' correlation, see inference::trace).
        let (mut err, mut total) = (0.0f64, 0.0f64);
        for p in (0..r.pixel_count()).filter(|&p| interior[p]) {
            for c in 0..3 {
                err += f64::from((r.composite[p][c] - r.beauty[p][c]).abs());
                total += f64::from(r.beauty[p][c]);
            }
        }
        assert!(
            total > 0.0 && err / total < 0.15,
            "relative error {}",
            err / total
        );
        assert!(r.composite.iter().flatten().all(|v| v.is_finite()));
        Ok(())
    }

    #[test]
    fn wrong_object_or_settings_are_errors_before_tracing() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let scene = teapot(dir.path())?;
        let refs_dir = dir.path().join("refs");
        let refs = References::new(&scene, &refs_dir, tiny())?;
        for object in ["floor", "light", "no such thing"] {
            let e = refs
                .get(View::on_orbit(0.0), object)
                .err()
                .map(|e| format!("{e:#}"));
            assert!(
                e.as_ref()
                    .is_some_and(|e| e.contains(object) && e.contains("teapot")),
                "{e:?}"
            );
        }
        assert!(!refs_dir.exists(), "nothing traced or written");
        let zero = TraceSettings { spp: 0, ..tiny() };
        assert!(References::new(&scene, &refs_dir, zero).is_err());
        Ok(())
    }

    #[test]
    fn negative_zero_is_zero() {
        let v = View::new(-0.0, -0.0);
        assert!(v.azimuth_deg.is_sign_positive() && v.elevation_deg.is_sign_positive());
    }
}
