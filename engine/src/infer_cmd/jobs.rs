//! Which maps a scene asks for: per reflector with EM settings, each EM
//! layer on its geometry, on request one sphere-at-infinity EM for its
//! whole specular appearance, and its PTM.

use anyhow::{Result, bail};
use glam::Vec3;
use inference::em_geometry::{EmGeometry, bounding_ellipsoid};
use inference::scene::{EmLayer, Material, Object, Scene};
use inference::solve::SolveOptions;
use inference::solve::layout::TextureShape;
use std::hash::{Hash, Hasher};

/// What a job infers.
#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    /// An EM layer on its geometry, indexed by texgen.
    Em(EmLayer, EmGeometry),
    /// One EM on its geometry for the reflector's whole specular
    /// appearance, local over distant (`infer --sphere`: the single
    /// sphere-at-infinity PEM the layered one is compared with).
    Whole(EmGeometry),
    /// A parameterized texture map: the reflector's whole appearance as a
    /// 2D texture on its own texture coordinates.
    Ptm,
}

/// One map of one reflector to infer.
pub(super) struct Job<'a> {
    pub(super) object: &'a Object,
    pub(super) kind: Kind,
    pub(super) origin: Vec3,
    pub(super) resolution: u32,
}

impl Job<'_> {
    pub(super) fn name(&self) -> String {
        let layer = match self.kind {
            Kind::Em(EmLayer::Distant, _) => "specular_distant",
            Kind::Em(EmLayer::Local, _) => "specular_local",
            Kind::Whole(_) => "specular_sphere",
            Kind::Ptm => "ptm",
        };
        format!("{}.{layer}", self.object.name)
    }
    pub(super) fn channels(&self) -> usize {
        match self.kind {
            Kind::Em(EmLayer::Local, _) => 4,
            _ => 3,
        }
    }
    pub(super) fn shape(&self) -> TextureShape {
        match self.kind {
            Kind::Em(..) | Kind::Whole(_) => TextureShape::Cube {
                size: self.resolution,
            },
            Kind::Ptm => TextureShape::Tex2D {
                width: self.resolution,
                height: self.resolution,
            },
        }
    }
}

/// The maps the scene asks for: per reflective object with EM settings,
/// its EM layers, with `sphere` its whole specular appearance on one
/// sphere-at-infinity EM (same resolution), then its PTM.
pub(super) fn jobs_for<'a>(
    scene: &'a Scene,
    em_size: Option<u32>,
    sphere: bool,
) -> Result<Vec<Job<'a>>> {
    let (room_min, room_max) = scene.bounds();
    let mut jobs = Vec::new();
    for object in &scene.objects {
        let reflective = matches!(
            scene.materials.get(object.material),
            Some(Material::Mirror { .. } | Material::Glossy { .. })
        );
        let Some(em) = object.em.as_ref().filter(|_| reflective) else {
            continue;
        };
        let resolution = em_size.unwrap_or(em.resolution);
        if resolution == 0 || !resolution.is_power_of_two() || resolution > 2048 {
            bail!(
                "--em-size / {}: EM resolution {resolution} (expected a power of two up to 2048)",
                object.name
            );
        }
        let origin = object.mesh.area_weighted_centroid();
        for &layer in &em.layers {
            let geometry = match layer {
                EmLayer::Distant => EmGeometry::Box {
                    min: room_min,
                    max: room_max,
                },
                EmLayer::Local => EmGeometry::Ellipsoid {
                    center: origin,
                    radii: bounding_ellipsoid(origin, &object.mesh.positions),
                },
            };
            jobs.push(Job {
                object,
                kind: Kind::Em(layer, geometry),
                origin,
                resolution,
            });
        }
        if sphere {
            jobs.push(Job {
                object,
                kind: Kind::Whole(EmGeometry::SphereAtInfinity),
                origin,
                resolution,
            });
        }
        jobs.push(Job {
            object,
            kind: Kind::Ptm,
            origin,
            resolution,
        });
    }
    Ok(jobs)
}

/// What a map was inferred from: the traced target, the job (its name,
/// kind with geometry, origin, resolution), the solve options, the image
/// size and the reflector's mesh. A map whose `.key` file holds this is up
/// to date. Any change here re-infers every map already made (the teapot's
/// 100 samples took 36 min), so new kinds of job must leave the keys of the
/// existing ones as they are.
pub(super) fn inputs_key(
    trace_key: u64,
    job: &Job,
    options: &SolveOptions,
    size: (u32, u32),
) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (trace_key, job.name(), job.resolution, size).hash(&mut h);
    format!(
        "{:?} {:?} {:?} {:?}",
        job.kind, job.origin, options.eps_f, options.eps_b
    )
    .hash(&mut h);
    // The reflector's mesh decides texgen.
    for p in &job.object.mesh.positions {
        p.to_array().map(f32::to_bits).hash(&mut h);
    }
    h.finish()
}
