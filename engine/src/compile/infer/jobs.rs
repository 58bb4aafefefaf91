//! Which maps a scene asks for — per reflector with EM settings, each EM
//! layer on its geometry, on request one sphere-at-infinity EM for its
//! whole specular appearance, and its PTM — and the key of each.

use crate::maps::{MapLayer, ptm_edge, reflective};
use anyhow::{Result, bail};
use glam::Vec3;
use inference::atlas;
use inference::em_geometry::{EmGeometry, bounding_ellipsoid};
use inference::key::{Fnv, Key};
use inference::scene::{EM_RESOLUTIONS, EmLayer, Mesh, Object, Orbit, Scene};
use inference::solve::SolveOptions;
use inference::solve::layout::TextureShape;
use std::hash::Hasher;
use std::sync::Arc;

/// Bump when a change to inference changes the maps it makes.
pub const INFERENCE_VERSION: u32 = 3;

/// The views a job's solves stack beside the sample's own: `deg` either
/// side on its ring (None: the neighbouring samples), then `above_deg`
/// above it, at its azimuth or (`above_spacing`) at the nearest azimuth of
/// a grid that many degrees apart.
#[derive(Clone, Debug, PartialEq)]
pub struct Stack {
    pub deg: Option<f32>,
    pub above_deg: Vec<f32>,
    pub above_spacing: Option<f32>,
}

/// A view stacked into a sample's solves: another sample's trace, or a
/// free view (`view_az±A_el±E`) at (azimuth, elevation) in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StackedView {
    Sample(u32),
    Free(f32, f32),
}

/// The views stacked into sample `k`'s solves: its neighbouring samples'
/// (`stack.deg` None) or the views `deg` degrees either side of it on its
/// ring, then those `stack.above_deg` above it at its azimuth, or at the
/// grid azimuth nearest it (`stack.above_spacing`), on the first ring. A sample's own trace
/// where one sits at a view, else a free view (shared by the samples
/// either side of it when they lie 2·`deg` apart, and by those nearest one
/// grid azimuth).
pub fn stacked_views_of(orbit: &Orbit, k: u32, stack: &Stack) -> Vec<StackedView> {
    let (azimuth, elevation) = orbit.sample_angles(k);
    let at = |a: f32, e: f32| {
        (0..orbit.sample_count())
            .find(|&n| orbit.sample_angles(n) == (a, e))
            .map_or(StackedView::Free(a, e), StackedView::Sample)
    };
    let mut views: Vec<StackedView> = match stack.deg {
        None => ring_neighbours(k, orbit.ring_position(k))
            .into_iter()
            .map(StackedView::Sample)
            .collect(),
        Some(deg) => vec![at(azimuth - deg, elevation), at(azimuth + deg, elevation)],
    };
    let above = match stack.above_spacing {
        Some(d) => nearest_on_grid(azimuth, orbit.sample_angles(0).0, d),
        None => azimuth,
    };
    if stacks_above(orbit, k) {
        views.extend(stack.above_deg.iter().map(|&e| at(above, elevation + e)));
    }
    views
}

/// Whether sample `k` stacks the views above: only the first ring's
/// samples do (the rings above it are views above themselves).
pub fn stacks_above(orbit: &Orbit, k: u32) -> bool {
    orbit.sample_line_ring(k).1 == 0
}

/// The azimuth of the grid `start + i·spacing` nearest `azimuth` (ties
/// away from the start); `azimuth` itself for a spacing that is not
/// positive and finite.
fn nearest_on_grid(azimuth: f32, start: f32, spacing: f32) -> f32 {
    if !(spacing.is_finite() && spacing > 0.0) {
        return azimuth;
    }
    start + ((azimuth - start) / spacing).round() * spacing
}

/// One map of one reflector to infer.
pub struct Job<'a> {
    pub object: &'a Object,
    pub layer: MapLayer,
    /// Where texgen intersects reflected rays (None for the PTM).
    pub geometry: Option<EmGeometry>,
    pub origin: Vec3,
    pub resolution: u32,
    /// The PTM's mesh on its atlas (`inference::atlas`), what its probe
    /// renders draw; None for an EM.
    pub atlas: Option<Arc<Mesh>>,
}

impl Job<'_> {
    /// `<object>.<layer>`.
    pub fn name(&self) -> String {
        format!("{}.{}", self.object.name, self.layer.file_part())
    }
    pub fn channels(&self) -> usize {
        self.layer.channels()
    }
    pub fn shape(&self) -> TextureShape {
        self.layer.shape(self.resolution)
    }
    /// The weight of the neighbouring samples' views in this job's solve:
    /// the object's `neighbour_weight` for every layer, so the sphere PEM
    /// and PTM baselines are solved from the same traced views as the
    /// layered PEM they are ranked against.
    pub fn neighbour_weight(&self) -> f32 {
        self.object.neighbour_weight()
    }
    /// Where this job's stacked views lie, when it stacks any: the
    /// object's `neighbour_deg` either side of the sample, or (None) the
    /// neighbouring samples.
    pub fn neighbour_deg(&self) -> Option<f32> {
        (self.neighbour_weight() > 0.0)
            .then(|| self.object.neighbour_deg())
            .flatten()
    }

    /// The elevations above its sample of the further views this job
    /// stacks (`[objects.em] neighbour_above_deg`); empty when it stacks
    /// none.
    pub fn neighbour_above_deg(&self) -> &[f32] {
        if self.neighbour_weight() > 0.0 {
            self.object.neighbour_above_deg()
        } else {
            &[]
        }
    }

    /// The weight of the views above in this job's solve
    /// (`[objects.em] neighbour_above_weight`, else `neighbour_weight`).
    pub fn neighbour_above_weight(&self) -> f32 {
        match self.object.neighbour_above_weight() {
            Some(w) if self.neighbour_weight() > 0.0 => w,
            _ => self.neighbour_weight(),
        }
    }

    /// Which views this job's solves stack beside the sample's own (None
    /// when it stacks none): jobs with equal stacks share their traces.
    pub fn stack(&self) -> Option<Stack> {
        (self.neighbour_weight() > 0.0).then(|| Stack {
            deg: self.neighbour_deg(),
            above_deg: self.neighbour_above_deg().to_vec(),
            above_spacing: self.object.neighbour_above_spacing_deg(),
        })
    }
}

/// The maps the scene asks for: per reflective object with EM settings,
/// its EM layers, with `sphere` its whole specular appearance on one
/// sphere-at-infinity EM (same resolution), then its PTM. `em_size`
/// overrides the scene's EM resolution.
pub fn jobs_for(scene: &Scene, em_size: Option<u32>, sphere: bool) -> Result<Vec<Job<'_>>> {
    let (room_min, room_max) = scene.bounds();
    let mut jobs = Vec::new();
    for object in scene.objects.iter().filter(|o| reflective(scene, o)) {
        let Some(em) = object.em.as_ref() else {
            continue;
        };
        let resolution = em_size.unwrap_or(em.resolution);
        if !resolution.is_power_of_two() || !EM_RESOLUTIONS.contains(&resolution) {
            bail!(
                "--em-size {resolution}: expected a power of two from {} to {}",
                EM_RESOLUTIONS.start(),
                EM_RESOLUTIONS.end()
            );
        }
        let origin = object.mesh.area_weighted_centroid();
        let job = |layer, geometry| Job {
            object,
            layer,
            geometry,
            origin,
            resolution,
            atlas: None,
        };
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
            jobs.push(job(MapLayer::from_em(layer), Some(geometry)));
        }
        if sphere {
            jobs.push(job(MapLayer::Sphere, Some(EmGeometry::SphereAtInfinity)));
        }
        let atlas = atlas::build(&object.mesh, ptm_edge(resolution)).mesh(&object.mesh);
        jobs.push(Job {
            atlas: Some(Arc::new(atlas)),
            ..job(MapLayer::Ptm, None)
        });
    }
    Ok(jobs)
}

/// The key of a map: the traced target's (scene parts, eye, trace
/// settings) plus the map's own inputs — the job (name, geometry, origin,
/// resolution), the solve options, the image size, the reflector's mesh and
/// the inference code's version. New kinds of job leave the keys of the
/// others as they are.
pub fn map_key(trace: &Key, job: &Job, options: &SolveOptions, size: (u32, u32)) -> Key {
    keyed_map(trace, map_settings(job, options, size))
}

/// [`map_key`] from the hash of the map's own inputs ([`map_settings`]),
/// which every sample of a job shares.
pub fn keyed_map(trace: &Key, settings: u64) -> Key {
    trace
        .clone()
        .with("inference version", u64::from(INFERENCE_VERSION))
        .with("map settings", settings)
}

/// The hash of a map's own inputs: the same for every sample of `job`
/// (it reads the whole mesh, so a compile hashes it once per job, not per
/// sample).
pub fn map_settings(job: &Job, options: &SolveOptions, size: (u32, u32)) -> u64 {
    let mut h = Fnv::default();
    h.str(&job.name());
    h.str(&format!("{:?} {:?}", job.geometry, job.origin));
    h.write_u32(job.resolution);
    h.write_u32(size.0);
    h.write_u32(size.1);
    h.str(&format!("{:?} {:?}", options.eps_f, options.eps_b));
    // Added with the local layer's prior: maps without one keep their keys.
    if options.eps_prior > 0.0 {
        h.f32(options.eps_prior);
    }
    // Added with the bounds: unbounded maps keep their keys.
    if options.eps_bound > 0.0 {
        h.str("bounds");
        h.f32(options.eps_bound);
    }
    // Added with display weights: maps fitted in linear radiance keep
    // their keys.
    if job.object.display_weight() {
        h.str("display weights");
    }
    // Added with the PTM's atlas (its texels were the mesh's own UVs):
    // the atlas itself, so any change of it re-solves the PTM.
    if let Some(atlas) = &job.atlas {
        h.str("atlas");
        atlas.uvs.iter().for_each(|&uv| h.v2(uv));
        atlas.indices.iter().for_each(|&i| h.write_u32(i));
    }
    // Added with the LOD bias: maps read without one keep their keys.
    if job.geometry.is_some() && job.object.lod_bias() != 0.0 {
        h.f32(job.object.lod_bias());
    }
    // Added with neighbouring views: maps solved from their own view alone
    // keep their keys.
    if job.neighbour_weight() > 0.0 {
        h.str("neighbours");
        h.f32(job.neighbour_weight());
        // Added with offset views: maps stacking their neighbouring
        // samples keep their keys.
        if let Some(deg) = job.neighbour_deg() {
            h.str("offset views");
            h.f32(deg);
        }
        // Added with views above: maps stacking none keep their keys.
        if !job.neighbour_above_deg().is_empty() {
            h.str("views above");
            for &e in job.neighbour_above_deg() {
                h.f32(e);
            }
            // Added with shared views above: views at every sample keep
            // their keys.
            if let Some(d) = job.object.neighbour_above_spacing_deg() {
                h.str("above spacing");
                h.f32(d);
            }
            // Added with their own weight: views above at
            // `neighbour_weight` keep their keys.
            if let Some(w) = job.object.neighbour_above_weight() {
                h.str("above weight");
                h.f32(w);
            }
        }
    }
    for p in &job.object.mesh.positions {
        h.v3(*p);
    }
    h.finish()
}

/// Sample `k`'s neighbours on its ring (azimuth line ± 1 of the ring's
/// own lines), `k` being at `pos` of the ring's `len` consecutive samples
/// ([`Orbit::ring_position`]), where they exist: a ring does not wrap, the
/// orbit is an arc.
pub(super) fn ring_neighbours(k: u32, (pos, len): (u32, u32)) -> Vec<u32> {
    let mut n = Vec::new();
    if pos > 0 {
        n.push(k - 1);
    }
    if pos + 1 < len {
        n.push(k + 1);
    }
    n
}

/// Which of a sample's neighbours its ring's ends cut off (the sample at
/// `pos` of `len`): bit 0 the previous azimuth line, bit 1 the next; 0 for
/// a sample inside the arc.
pub(super) fn missing_neighbours((pos, len): (u32, u32)) -> u64 {
    u64::from(pos == 0) | u64::from(pos + 1 >= len) << 1
}

#[cfg(test)]
mod tests {
    use super::{
        Job, Stack, StackedView, jobs_for, map_key, missing_neighbours, nearest_on_grid,
        ring_neighbours, stacked_views_of,
    };
    use crate::maps::MapLayer;
    use inference::key::Key;
    use inference::scene::Scene;
    use inference::solve::SolveOptions;
    use std::sync::Arc;

    #[test]
    fn the_neighbour_weight_keys_every_map() {
        let with = Scene::load("teapot").expect("the built-in teapot scene loads");
        assert!(
            with.object("teapot")
                .is_some_and(|o| o.neighbour_weight() > 0.0)
        );
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../assets/scenes/teapot.toml"
        ))
        .expect("teapot.toml");
        let text = inference::scene::shipped::without_views_above(&text);
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("t.toml");
        let without: String = text
            .lines()
            .filter(|l| !l.starts_with("neighbour_weight"))
            .map(|l| format!("{l}\n"))
            .collect();
        std::fs::write(&path, without).expect("write scene");
        let without = Scene::load(&path.to_string_lossy()).expect("loads without the line");
        let key = |scene: &Scene| -> Vec<(String, u64)> {
            let jobs = jobs_for(scene, None, true).expect("jobs");
            jobs.iter()
                .map(|j| {
                    let k = map_key(&Key::new(), j, &SolveOptions::default(), (64, 48));
                    (j.name(), k.hash())
                })
                .collect()
        };
        let (with, without) = (key(&with), key(&without));
        assert_eq!(with.len(), 4, "distant, local, sphere, PTM");
        for ((name, a), (_, b)) in with.into_iter().zip(without) {
            assert_ne!(a, b, "{name}: every map stacks, so the weight is keyed");
        }
    }

    #[test]
    fn the_ptm_is_keyed_by_its_atlas() {
        let scene = Scene::load("teapot").expect("shipped teapot");
        let jobs = jobs_for(&scene, None, false).expect("jobs");
        let ptm = jobs.iter().find(|j| j.layer == MapLayer::Ptm).expect("PTM");
        let atlas = ptm.atlas.as_ref().expect("the PTM's atlas");
        assert_eq!(atlas.triangle_count(), ptm.object.mesh.triangle_count());
        assert!(
            jobs.iter()
                .filter(|j| j.layer != MapLayer::Ptm)
                .all(|j| j.atlas.is_none())
        );
        let key = |job: &Job| map_key(&Key::new(), job, &SolveOptions::default(), (64, 48));
        let mut moved = (**atlas).clone();
        moved.uvs[0].x += 1e-3;
        let other = Job {
            atlas: Some(Arc::new(moved)),
            ..job_like(ptm)
        };
        assert_ne!(key(ptm), key(&other), "a changed atlas re-solves the PTM");
        assert_eq!(key(ptm), key(&job_like(ptm)));
    }

    fn job_like<'a>(j: &Job<'a>) -> Job<'a> {
        Job {
            object: j.object,
            layer: j.layer,
            geometry: j.geometry,
            origin: j.origin,
            resolution: j.resolution,
            atlas: j.atlas.clone(),
        }
    }

    #[test]
    fn neighbours_stay_on_their_ring_and_inside_the_arc() {
        // 1D orbit of 3: the ends have one neighbour.
        assert_eq!(ring_neighbours(0, (0, 3)), vec![1]);
        assert_eq!(ring_neighbours(1, (1, 3)), vec![0, 2]);
        assert_eq!(ring_neighbours(2, (2, 3)), vec![1]);
        assert_eq!(
            [0, 1, 2].map(|k| missing_neighbours((k, 3))),
            [0b01, 0b00, 0b10]
        );
        // Ring 1 of 4-line rings: samples 4..8, never 3 or 8.
        let mut o = Scene::load("teapot").expect("teapot").orbit;
        (o.samples, o.rings, o.ring_line_every) = (4, 3, 1);
        let n = |o: &inference::scene::Orbit, k| ring_neighbours(k, o.ring_position(k));
        assert_eq!(
            [n(&o, 4), n(&o, 7), n(&o, 5)],
            [vec![5], vec![6], vec![4, 6]]
        );
        // Sparse upper rings (every 2nd line and the last of 4: 0, 2, 3):
        // ring 1 is samples 4..7, ring 2 7..10.
        o.ring_line_every = 2;
        assert_eq!(o.sample_count(), 10);
        let ns = [4, 6, 7, 9].map(|k| n(&o, k));
        assert_eq!(ns, [vec![5], vec![5], vec![8], vec![8]]);
        assert_eq!(o.sample_angles(6), (o.angle_deg(3), o.ring_elevation(1)));
        // A single sample has neither.
        assert_eq!(ring_neighbours(0, (0, 1)), Vec::<u32>::new());
        assert_eq!(missing_neighbours((0, 1)), 0b11);
    }

    #[test]
    fn views_above_take_their_own_weight_in_every_maps_solves() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../assets/scenes/teapot.toml"
        ))
        .expect("teapot.toml");
        let text = inference::scene::shipped::without_views_above(&text);
        let weights = |extra: &str| -> Vec<(f32, f32)> {
            let dir = tempfile::tempdir().expect("temp dir");
            let path = dir.path().join("t.toml");
            let line = "neighbour_weight = 1.0";
            let edited = text.replacen(line, &format!("neighbour_weight = 0.5\n{extra}"), 1);
            std::fs::write(&path, edited).expect("write scene");
            let scene = Scene::load(&path.to_string_lossy()).expect("scene loads");
            let jobs = jobs_for(&scene, None, true).expect("jobs");
            jobs.iter()
                .map(|j| (j.neighbour_weight(), j.neighbour_above_weight()))
                .collect()
        };
        // Distant, local, sphere, PTM: every map stacks the same views.
        let set = weights("neighbour_above_deg = [12.0]\nneighbour_above_weight = 0.25");
        assert_eq!(set, [(0.5, 0.25); 4]);
        let unset = weights("neighbour_above_deg = [12.0]");
        assert_eq!(unset, [(0.5, 0.5); 4]);
    }

    #[test]
    fn shared_views_above_sit_on_the_grid_nearest_each_sample() {
        assert_eq!(nearest_on_grid(5.0, 0.0, 4.0), 4.0);
        assert_eq!(
            nearest_on_grid(6.0, 0.0, 4.0),
            8.0,
            "ties away from the start"
        );
        assert_eq!(nearest_on_grid(-3.0, 1.0, 4.0), -3.0);
        assert_eq!(nearest_on_grid(7.5, 0.0, f32::NAN), 7.5);
        assert_eq!(nearest_on_grid(7.5, 0.0, 0.0), 7.5);
        // The built-in orbit: samples 1° apart from 0°; a 4° grid puts
        // samples 0-1 on 0°, 2-5 on 4°, and stacks the ring neighbours too.
        let scene = Scene::load("teapot").expect("the built-in teapot scene loads");
        let stack = Stack {
            deg: None,
            above_deg: vec![15.0],
            above_spacing: Some(4.0),
        };
        let above = |k| stacked_views_of(&scene.orbit, k, &stack)[2..].to_vec();
        assert_eq!(above(1), [StackedView::Free(0.0, 15.0)]);
        assert_eq!(above(2), [StackedView::Free(4.0, 15.0)]);
        assert_eq!(above(5), [StackedView::Free(4.0, 15.0)]);
        assert_eq!(
            stacked_views_of(&scene.orbit, 1, &stack)[..2],
            [StackedView::Sample(0), StackedView::Sample(2)]
        );
        let per_sample = Stack {
            above_spacing: None,
            ..stack
        };
        assert_eq!(
            stacked_views_of(&scene.orbit, 5, &per_sample)[2..],
            [StackedView::Free(5.0, 15.0)]
        );
    }
}
