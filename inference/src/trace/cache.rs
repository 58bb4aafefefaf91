//! The cache key of a traced image: a hash of everything that determines its pixels
//! (scene content, eye, settings, tracer version), not of file names or times.

use std::hash::Hasher;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::error::TraceError;
use super::{Caustics, TraceSettings};
use crate::scene::{Material, Scene};

/// Bump when a change to the tracer changes its images (2: caustics).
pub const TRACER_VERSION: u32 = 2;

/// FNV-1a, 64-bit: stable across runs, platforms and Rust versions (unlike `DefaultHasher`).
struct Fnv(u64);

impl Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

impl Fnv {
    fn f(&mut self, x: f32) {
        self.write_u32(x.to_bits());
    }
    fn v3(&mut self, v: Vec3) {
        v.to_array().into_iter().for_each(|x| self.f(x));
    }
    fn v2(&mut self, v: Vec2) {
        v.to_array().into_iter().for_each(|x| self.f(x));
    }
    fn s(&mut self, s: &str) {
        self.write_u64(s.len() as u64);
        self.write(s.as_bytes());
    }
}

/// Key of the image `settings` produce of `scene` from `eye` (threads and progress excluded:
/// they do not change pixels).
pub fn key(scene: &Scene, eye: Vec3, settings: &TraceSettings) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.write_u32(TRACER_VERSION);
    h.v3(eye);
    h.write_u32(settings.width);
    h.write_u32(settings.height);
    h.write_u32(settings.spp);
    h.write_u64(settings.seed);
    let t = &settings.transport;
    h.v3(t.background);
    h.write_u32(t.max_diffuse_bounces);
    h.write_u32(t.max_specular_bounces);
    match t.caustics {
        Caustics::Off => h.write_u8(0),
        Caustics::Paths => h.write_u8(1),
        Caustics::Photons { photons, radius } => {
            h.write_u8(2);
            h.write_u32(photons);
            h.f(radius);
        }
    }

    let c = &scene.camera;
    [c.fov_y_deg, c.near, c.far]
        .into_iter()
        .for_each(|x| h.f(x));
    let o = &scene.orbit;
    h.v3(o.center);
    [o.radius, o.height, o.start_deg, o.step_deg]
        .into_iter()
        .for_each(|x| h.f(x));
    for l in &scene.lights {
        h.s(&l.name);
        [l.center, l.edge_u, l.edge_v, l.radiance]
            .into_iter()
            .for_each(|v| h.v3(v));
    }
    for (m, name) in scene.materials.iter().zip(&scene.material_names) {
        h.s(name);
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
                h.f(roughness);
            }
            Material::Glass { ior, absorption } => {
                h.write_u8(3);
                h.f(ior);
                h.v3(absorption);
            }
            Material::Emissive { radiance } => {
                h.write_u8(4);
                h.v3(radiance);
            }
        }
    }
    for obj in &scene.objects {
        h.s(&obj.name);
        h.write_u64(obj.material as u64);
        let m = &obj.mesh;
        h.write_u64(m.positions.len() as u64);
        m.positions.iter().for_each(|&p| h.v3(p));
        m.normals.iter().for_each(|&n| h.v3(n));
        m.uvs.iter().for_each(|&uv| h.v2(uv));
        m.indices.iter().for_each(|&i| h.write_u32(i));
    }
    for tex in &scene.textures {
        h.write_u32(tex.width);
        h.write_u32(tex.height);
        tex.texels
            .iter()
            .flatten()
            .for_each(|&x| h.write_u32(x.to_bits()));
    }
    h.finish()
}

/// The file beside `<stem>.exr` that records the key it was traced with.
pub fn key_path(stem: &Path) -> PathBuf {
    super::output::with_suffix(stem, ".key")
}

/// True when `<stem>.exr` and `<stem>.png` exist and were traced with `key`.
pub fn is_fresh(stem: &Path, key: u64) -> bool {
    let recorded = std::fs::read_to_string(key_path(stem)).ok();
    recorded.is_some_and(|r| r.trim() == format!("{key:016x}"))
        && super::output::with_suffix(stem, ".exr").is_file()
        && super::output::with_suffix(stem, ".png").is_file()
}

/// Records `key` for `<stem>` (atomically, after the images are in place).
pub fn record(stem: &Path, key: u64) -> Result<(), TraceError> {
    let path = key_path(stem);
    let tmp = super::output::temp_name(&path);
    std::fs::write(&tmp, format!("{key:016x}\n")).map_err(|e| TraceError::io(&tmp, e))?;
    std::fs::rename(&tmp, &path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        TraceError::io(&path, e)
    })
}
