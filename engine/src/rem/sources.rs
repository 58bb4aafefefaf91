//! The source maps of reflection-space IBR: one radiance environment map
//! per view direction of the geodesic sphere, as a sphere map seen from
//! that direction, made by the tracer. Each texel holds the reflector's
//! BRDF pre-integrated with the room's radiance from the reflector's EM
//! origin (its area-weighted centroid, as the static EM): for a mirror
//! `F(n·v) · L(r)`, for a glossy material `F(n·v) · mean L(ω)` over
//! directions drawn from its Phong lobe around `r`, the tracer's own lobe;
//! for a diffuse reflector `albedo · mean L(ω)` over cosine-distributed
//! directions around `n` (its irradiance over π: a lobe centred on the
//! normal, warped by `g_normal` — [`RemWarp`]).
//! Cached under `<out>/rem/` with the key of what made them.

use super::geometry::{Geodesic, g_mirror, g_normal, view_frame};
use anyhow::{Context, Result, bail};
use glam::{Vec2, Vec3};
use inference::key::{Fnv, Freshness, Key, freshness, read_verified, write_record};
use inference::scene::{Material, Mesh, Scene};
use inference::trace::rng::{Rng, cosine_hemisphere, phong_lobe};
use inference::trace::{TraceSettings, Tracer, cache, phong_exponent};
use rayon::prelude::*;
use std::hash::Hasher;
use std::path::{Path, PathBuf};

/// Bumped when the maps change for the same inputs (3: a reflector's
/// parts are seen through and the maps centred on all of them).
const REM_VERSION: u64 = 3;
const MAGIC: &[u8; 8] = b"PEMREM01";
const HEADER: usize = 16;

/// What decides the source maps besides the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RemSettings {
    /// Sphere-map resolution (texels per side).
    pub size: u32,
    /// Subdivisions of the icosahedron (0: its 12 vertices; 1: 42 views).
    pub level: u32,
    /// Paths per texel (the room's radiance is a noisy estimate).
    pub spp: u32,
    /// Glossy materials: lobe directions per texel (at least `spp`).
    pub lobe_samples: u32,
}

impl Default for RemSettings {
    fn default() -> Self {
        Self {
            size: 256,
            level: 0,
            spp: 16,
            lobe_samples: 64,
        }
    }
}

/// How a reflector's maps are warped between views (the paper's `g`):
/// by the mirror direction for lobes centred on it (mirror, glossy), by
/// the normal for a lobe centred on the normal (diffuse).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RemWarp {
    Mirror,
    Normal,
}

impl RemWarp {
    /// The warp object `object`'s material needs (None: no REM maps).
    pub fn of(scene: &Scene, object: usize) -> Option<RemWarp> {
        let material = scene.objects.get(object)?.material;
        match scene.materials.get(material)? {
            Material::Mirror { .. } | Material::Glossy { .. } => Some(RemWarp::Mirror),
            Material::Diffuse { .. } => Some(RemWarp::Normal),
            _ => None,
        }
    }
}

/// One reflector's source maps, RGBA (A = 1 inside the disk, 0 outside).
#[derive(Clone, Debug)]
pub struct SourceMaps {
    pub object: usize,
    pub size: u32,
    pub geodesic: Geodesic,
    /// `geodesic.vertices.len()` maps of `size²` texels, row t = 0 first.
    pub texels: Vec<[f32; 4]>,
    /// Seconds the tracer took (0 when read from the cache).
    pub trace_s: f64,
}

impl SourceMaps {
    /// Map `index`'s texels.
    pub fn map(&self, index: usize) -> &[[f32; 4]] {
        let n = (self.size * self.size) as usize;
        &self.texels[index * n..(index + 1) * n]
    }

    /// The texels as the device uploads them.
    /// `parts`: the objects the maps are drawn on ([`Scene::local_group`]).
    pub fn upload(&self, warp: RemWarp, parts: Vec<usize>) -> crate::passes::rem::SourceTexels<'_> {
        crate::passes::rem::SourceTexels {
            size: self.size,
            count: self.geodesic.vertices.len() as u32,
            texels: &self.texels,
            parts,
            normal_warp: warp == RemWarp::Normal,
        }
    }

    /// Bytes the maps take on the device (RGBA, 16-bit floats).
    pub fn device_bytes(&self) -> u64 {
        self.texels.len() as u64 * 8
    }
}

/// The reflector the maps are made for: the first mirror, glossy or
/// diffuse object with `[objects.em]` settings.
pub fn reflector(scene: &Scene) -> Result<usize> {
    (0..scene.objects.len())
        .find(|&i| scene.objects[i].em.is_some() && RemWarp::of(scene, i).is_some())
        .with_context(|| {
            format!(
                "{}: reflection-space IBR needs a mirror, glossy or diffuse object with \
                 [objects.em]",
                scene.origin
            )
        })
}

/// `<out>/rem/<object>.<size>.l<level>.rem`: each resolution and
/// subdivision has its own file, so rows that alternate them keep both.
pub fn maps_path(out: &Path, scene: &Scene, object: usize, settings: RemSettings) -> PathBuf {
    out.join("rem").join(format!(
        "{}.{}.l{}.rem",
        scene.objects[object].name, settings.size, settings.level
    ))
}

/// The source maps of `scene`'s reflector: read when fresh under `out`,
/// else traced and written there.
pub fn source_maps(scene: &Scene, out: &Path, settings: RemSettings) -> Result<SourceMaps> {
    if settings.size < 4 || settings.size > 2048 || settings.level > 3 || settings.spp == 0 {
        bail!(
            "reflection-space IBR: size {} (expected 4–2048), subdivision {} (0–3), spp {} (≥ 1)",
            settings.size,
            settings.level,
            settings.spp
        );
    }
    let object = reflector(scene)?;
    let path = maps_path(out, scene, object, settings);
    let key = maps_key(scene, settings);
    let why = match freshness(&path, &key) {
        Freshness::Fresh => match read(&path, object, settings) {
            Ok(maps) => return Ok(maps),
            Err(e) => format!("{e:#}"),
        },
        Freshness::Missing => "missing".into(),
        Freshness::Stale(what) => format!("{} changed", what.join(", ")),
        Freshness::Broken(why) => why,
    };
    eprintln!(
        "{}: tracing {} reflection-space source maps of {}² ({why})",
        scene.name,
        Geodesic::new(settings.level).vertices.len(),
        settings.size
    );
    let maps = trace(scene, object, settings)?;
    crate::util::files::claim_dir(path.parent().unwrap_or(out))?;
    crate::util::files::check_overwrite_keyed(&path)?;
    crate::util::files::write(&path, &encode(&maps))?;
    write_record(&path, &key)?;
    Ok(maps)
}

/// What the maps depend on: the scene, the tracer, the settings.
fn maps_key(scene: &Scene, settings: RemSettings) -> Key {
    let mut h = Fnv::default();
    for x in [
        settings.size,
        settings.level,
        settings.spp,
        settings.lobe_samples,
    ] {
        h.write_u32(x);
    }
    let t = inference::trace::Transport::default();
    h.v3(t.background);
    h.write_u32(t.max_diffuse_bounces);
    h.write_u32(t.max_specular_bounces);
    Key::new()
        .with("rem version", REM_VERSION)
        .with(
            "tracer version",
            u64::from(inference::trace::cache::TRACER_VERSION),
        )
        .merged(&cache::scene_key(scene))
        .with("rem settings", h.finish())
}

/// Traces every map (all cores).
pub fn trace(scene: &Scene, object: usize, settings: RemSettings) -> Result<SourceMaps> {
    let start = std::time::Instant::now();
    let geodesic = Geodesic::new(settings.level);
    let texels = trace_views(scene, object, settings, &geodesic.vertices)?;
    Ok(SourceMaps {
        object,
        size: settings.size,
        geodesic,
        texels,
        trace_s: start.elapsed().as_secs_f64(),
    })
}

/// The radiance sphere map of `object` seen from each of `views` (unit
/// directions from its EM origin), map-major, RGBA.
pub fn trace_views(
    scene: &Scene,
    object: usize,
    settings: RemSettings,
    views: &[Vec3],
) -> Result<Vec<[f32; 4]>> {
    let obj = &scene.objects[object];
    let lobe = match scene.materials.get(obj.material) {
        Some(Material::Mirror { f0 }) => Lobe::Mirror(*f0),
        Some(Material::Glossy { f0, roughness }) => Lobe::Phong(*f0, phong_exponent(*roughness)),
        Some(Material::Diffuse { albedo, .. }) => Lobe::Lambert(*albedo),
        _ => bail!("{}: not a mirror, glossy or diffuse object", obj.name),
    };
    // The reflector's parts (lid and body) are one reflector: maps seen
    // from their common centroid, through all of them.
    let parts = scene.local_group(object);
    let origin = group_origin(scene, &parts);
    let tracer = Tracer::new(scene)?;
    let trace_settings = TraceSettings::default();
    let size = settings.size as usize;
    let samples = match lobe {
        Lobe::Mirror(_) => settings.spp,
        _ => settings.lobe_samples.max(settings.spp),
    };
    Ok(tracer.with_integrator(&trace_settings, |integ, bvh| {
        let radiance = |dir: Vec3, rng: &mut Rng| {
            let mut rays = 0;
            let outside = |o: u32| !parts.contains(&(o as usize));
            match bvh.closest_where(origin, dir, 0.0, f32::INFINITY, outside) {
                Some(hit) => integ.radiance_at(hit, dir, 1, rng, &mut rays),
                None => trace_settings.transport.background,
            }
        };
        // Each path through a random point of the texel: texels are box
        // filtered (no aliasing of the room's bricks and checks).
        let texel = |index: usize| -> [f32; 4] {
            let (map, i) = (index / (size * size), index % (size * size));
            let corner = Vec2::new((i % size) as f32, (i / size) as f32);
            if g_normal((corner + 0.5) / size as f32).is_none() {
                return [0.0; 4];
            }
            let frame = view_frame(views[map]);
            let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
            for s in 0..samples {
                let mut rng = Rng::new(0, index as u64, s, 7);
                let jitter = Vec2::new(rng.next_f32(), rng.next_f32());
                let p = (corner + jitter) / size as f32;
                let (Some(n), Some(r)) = (g_normal(p), g_mirror(p)) else {
                    continue;
                };
                let (n_w, r_w) = (frame * n, (frame * r).normalize());
                // (A mirror draws no lobe numbers: its stream stays as it was.)
                let (dir, scale) = match lobe {
                    Lobe::Mirror(f0) => (r_w, inference::schlick_fresnel(f0, n.z)),
                    Lobe::Phong(f0, e) => {
                        let (u1, u2) = (rng.next_f32(), rng.next_f32());
                        let d = above(phong_lobe(r_w, e, u1, u2), n_w);
                        (d, inference::schlick_fresnel(f0, n.z))
                    }
                    Lobe::Lambert(albedo) => {
                        let (u1, u2) = (rng.next_f32(), rng.next_f32());
                        (cosine_hemisphere(n_w, u1, u2), albedo)
                    }
                };
                sum += scale * radiance(dir, &mut rng);
                weight += 1.0;
            }
            let c = sum / weight.max(1.0);
            [c.x, c.y, c.z, 1.0]
        };
        (0..views.len() * size * size)
            .into_par_iter()
            .map(texel)
            .collect()
    }))
}

/// The EM origin of a reflector made of `parts` ([`Scene::local_group`]):
/// their common area-weighted centroid.
pub fn group_origin(scene: &Scene, parts: &[usize]) -> Vec3 {
    Mesh::centroid_of(
        parts
            .iter()
            .filter_map(|&i| Some(&scene.objects.get(i)?.mesh)),
    )
}

/// What a source texel integrates: Fresnel times the radiance along the
/// mirror direction or over a Phong lobe around it (f0, exponent), or the
/// albedo times the cosine-weighted mean radiance around the normal.
#[derive(Clone, Copy)]
enum Lobe {
    Mirror(Vec3),
    Phong(Vec3, f32),
    Lambert(Vec3),
}

/// `d` mirrored into the hemisphere around `n` when it points below it.
fn above(d: Vec3, n: Vec3) -> Vec3 {
    let c = d.dot(n);
    if c >= 0.0 { d } else { d - 2.0 * c * n }
}

fn encode(maps: &SourceMaps) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER + maps.texels.len() * 16);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&maps.size.to_le_bytes());
    bytes.extend_from_slice(&(maps.geodesic.vertices.len() as u32).to_le_bytes());
    for t in &maps.texels {
        for c in t {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    bytes
}

/// The maps in `path` (whole, as its record says), checked against the
/// settings they should have been made with.
fn read(path: &Path, object: usize, settings: RemSettings) -> Result<SourceMaps> {
    let bytes = read_verified(path).map_err(anyhow::Error::msg)?;
    let geodesic = Geodesic::new(settings.level);
    let count = geodesic.vertices.len();
    let n = (settings.size * settings.size) as usize;
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
    };
    if bytes.get(..8) != Some(MAGIC.as_slice())
        || word(8) != Some(settings.size)
        || word(12) != Some(count as u32)
        || bytes.len() != HEADER + count * n * 16
    {
        bail!(
            "{}: expected {count} reflection-space maps of {}² ({} bytes)",
            path.display(),
            settings.size,
            HEADER + count * n * 16
        );
    }
    let floats: Vec<f32> = bytes[HEADER..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let texels = floats
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok(SourceMaps {
        object,
        size: settings.size,
        geodesic,
        texels,
        trace_s: 0.0,
    })
}
