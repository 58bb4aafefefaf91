//! The cache key of a traced image: named hashes of everything that
//! determines its pixels (scene content, eye, settings, tracer version), not
//! of file names or times. The scene's parts are hashed once per run
//! ([`scene_key`]), each image adds its eye and settings ([`image_key`]).

use std::hash::Hasher;
use std::path::Path;

use glam::Vec3;

use super::error::TraceError;
use super::{Caustics, TraceSettings};
use crate::key::{Fnv, Freshness, Key};
use crate::scene::{Material, Scene};

/// Bump when a change to the tracer changes its images (2: caustics).
pub const TRACER_VERSION: u32 = 2;

fn hash(f: impl FnOnce(&mut Fnv)) -> u64 {
    let mut h = Fnv::default();
    f(&mut h);
    h.finish()
}

/// The scene's content by part: camera, orbit, lights, materials, geometry
/// and textures (names included; the scene's file name is not).
pub fn scene_key(scene: &Scene) -> Key {
    let key = content_key(scene);
    // Reflectors that share a local layer (lid and body) change what the
    // layers hold; scenes with none keep their keys.
    let groups = scene.local_groups();
    if groups.iter().all(|g| g.len() <= 1) {
        return key;
    }
    key.with(
        "local groups",
        hash(|h| {
            for g in &groups {
                h.write_u64(g.len() as u64);
                g.iter().for_each(|&i| h.write_u64(i as u64));
            }
        }),
    )
}

fn content_key(scene: &Scene) -> Key {
    let c = &scene.camera;
    Key::new()
        .with(
            "camera",
            hash(|h| {
                [c.fov_y_deg, c.near, c.far]
                    .into_iter()
                    .for_each(|x| h.f32(x))
            }),
        )
        .with("orbit", hash(|h| orbit(h, &scene.orbit)))
        .with(
            "lights",
            hash(|h| {
                for l in &scene.lights {
                    h.str(&l.name);
                    [l.center, l.edge_u, l.edge_v, l.radiance]
                        .into_iter()
                        .for_each(|v| h.v3(v));
                }
                // Optional lights add bytes only when present: scenes without
                // them keep their keys.
                for l in &scene.directional_lights {
                    h.str("directional");
                    h.str(&l.name);
                    h.v3(l.to_light);
                    h.v3(l.irradiance);
                }
                for l in &scene.point_lights {
                    h.str("point");
                    h.str(&l.name);
                    h.v3(l.position);
                    h.v3(l.intensity);
                }
            }),
        )
        .with("materials", hash(|h| materials(h, scene)))
        .with("geometry", hash(|h| geometry(h, scene)))
        .with(
            "textures",
            hash(|h| {
                for tex in &scene.textures {
                    h.write_u32(tex.width);
                    h.write_u32(tex.height);
                    tex.texels
                        .iter()
                        .flatten()
                        .for_each(|&x| h.write_u32(x.to_bits()));
                }
            }),
        )
}

/// Where the samples' eyes are: the orbit and its ring and line layout.
fn orbit(h: &mut Fnv, o: &crate::scene::Orbit) {
    h.v3(o.center);
    [o.radius, o.height, o.start_deg, o.step_deg]
        .into_iter()
        .for_each(|x| h.f32(x));
    // With rings, sample k's eye depends on the ring layout
    // (1D orbits keep their keys).
    if o.rings > 1 {
        h.write_u32(o.samples);
        h.write_u32(o.rings);
        h.f32(o.ring_step_deg);
        // Sparse upper rings renumber their samples.
        if o.ring_line_every > 1 {
            h.str("ring line every");
            h.write_u32(o.ring_line_every);
        }
    }
    // Explicit lines: every one (even orbits keep their keys).
    if let Some(lines) = &o.azimuths {
        h.str("azimuths");
        lines.iter().for_each(|&a| h.f32(a));
    }
    // Explicit rings likewise (even rings keep their keys;
    // one ring at 0° is the 1D orbit).
    if let (Some(rings), true) = (&o.elevations, o.rings > 1) {
        h.str("elevations");
        rings.iter().for_each(|&e| h.f32(e));
    }
}

fn materials(h: &mut Fnv, scene: &Scene) {
    for (m, name) in scene.materials.iter().zip(&scene.material_names) {
        h.str(name);
        match *m {
            Material::Diffuse { albedo, texture } => {
                h.write_u8(0);
                h.v3(albedo);
                h.write_u64(texture.map_or(u64::MAX, |t| t as u64));
            }
            Material::Mirror { f0 } => {
                h.write_u8(1);
                h.v3(f0);
            }
            Material::Glossy { f0, roughness } => {
                h.write_u8(2);
                h.v3(f0);
                h.f32(roughness);
            }
            Material::Glass { ior, absorption } => {
                h.write_u8(3);
                h.f32(ior);
                h.v3(absorption);
            }
            Material::Emissive { radiance } => {
                h.write_u8(4);
                h.v3(radiance);
            }
        }
    }
}

fn geometry(h: &mut Fnv, scene: &Scene) {
    for obj in &scene.objects {
        h.str(&obj.name);
        h.write_u64(obj.material as u64);
        let m = obj.traced_mesh();
        h.write_u64(m.positions.len() as u64);
        m.positions.iter().for_each(|&p| h.v3(p));
        m.normals.iter().for_each(|&n| h.v3(n));
        m.uvs.iter().for_each(|&uv| h.v2(uv));
        m.indices.iter().for_each(|&i| h.write_u32(i));
    }
}

/// Key of the image `settings` produce of the scene (its [`scene_key`])
/// from `eye` (threads and progress excluded: they do not change pixels).
pub fn image_key(scene: &Key, eye: Vec3, settings: &TraceSettings) -> Key {
    let t = &settings.transport;
    Key::new()
        .with("tracer version", u64::from(TRACER_VERSION))
        .merged(scene)
        .with("eye", hash(|h| h.v3(eye)))
        .with(
            "trace settings",
            hash(|h| {
                h.write_u32(settings.width);
                h.write_u32(settings.height);
                h.write_u32(settings.spp);
                h.write_u64(settings.seed);
                h.v3(t.background);
                h.write_u32(t.max_diffuse_bounces);
                h.write_u32(t.max_specular_bounces);
                match t.caustics {
                    Caustics::Off => h.write_u8(0),
                    Caustics::Paths => h.write_u8(1),
                    Caustics::Photons { photons, radius } => {
                        h.write_u8(2);
                        h.write_u32(photons);
                        h.f32(radius);
                    }
                }
            }),
        )
}

/// Key of one image, hashing the scene too (for single images; loops over
/// many views should hash the scene once with [`scene_key`]).
pub fn key(scene: &Scene, eye: Vec3, settings: &TraceSettings) -> Key {
    image_key(&scene_key(scene), eye, settings)
}

/// Whether `<stem>.exr` and `<stem>.png` exist, whole, traced with `key`.
pub fn freshness(stem: &Path, key: &Key) -> Freshness {
    if !super::output::with_suffix(stem, ".png").is_file() {
        return Freshness::Missing;
    }
    crate::key::freshness(&super::output::with_suffix(stem, ".exr"), key)
}

/// Records `key` for `<stem>.exr` (after the images are in place), with
/// the `seconds` the trace took when known.
pub fn record(stem: &Path, key: &Key, seconds: Option<f64>) -> Result<(), TraceError> {
    let exr = super::output::with_suffix(stem, ".exr");
    crate::key::write_record_timed(&exr, key, seconds).map_err(|e| TraceError::io(&exr, e.source))
}
