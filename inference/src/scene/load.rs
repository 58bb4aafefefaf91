//! From a parsed scene file to a validated `Scene`: every check names the file and field.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Quat, Vec3};

use super::camera::{Camera, Orbit};
use super::error::SceneError;
use super::file::{MaterialFile, MeshFile, ObjectFile, SceneFile, TextureFile, V3};
use super::light::AreaLight;
use super::material::{EmSettings, Material};
use super::mesh::Mesh;
use super::obj::load_obj;
use super::texture::Texture;
use super::{Object, Scene, room};
use crate::teapot::{self, DEFAULT_SEGMENTS, MAX_SEGMENTS, TeapotPart};

const MAX_TEXTURE_RESOLUTION: u32 = 8192;
const MAX_EM_RESOLUTION: u32 = 8192;

/// Validation context: the scene file, for error messages, and the mesh cache.
pub struct Loader<'a> {
    pub path: &'a Path,
    pub cache_dir: &'a Path,
}

impl Loader<'_> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.to_owned(),
            field: field.into(),
            message: message.into(),
        }
    }

    fn vec3(&self, field: &str, v: V3) -> Result<Vec3, SceneError> {
        let v = Vec3::from_array(v);
        if !v.is_finite() {
            return Err(self.err(field, format!("{v:?} is not finite (expected numbers)")));
        }
        Ok(v)
    }

    /// Finite, each component in `[lo, hi]`.
    fn vec3_in(&self, field: &str, v: V3, lo: f32, hi: f32) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v)?;
        if v.cmplt(Vec3::splat(lo)).any() || v.cmpgt(Vec3::splat(hi)).any() {
            return Err(self.err(field, format!("{v:?} outside [{lo}, {hi}]")));
        }
        Ok(v)
    }

    fn finite(&self, field: &str, x: f32) -> Result<f32, SceneError> {
        if !x.is_finite() {
            return Err(self.err(field, format!("{x} is not finite")));
        }
        Ok(x)
    }

    fn positive(&self, field: &str, x: f32) -> Result<f32, SceneError> {
        if !(x > 0.0 && x.is_finite()) {
            return Err(self.err(field, format!("{x} must be positive and finite")));
        }
        Ok(x)
    }

    pub fn build(&self, file: SceneFile) -> Result<Scene, SceneError> {
        let name = file.name.clone().unwrap_or_else(|| {
            self.path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        let camera = self.camera(&file)?;
        let orbit = self.orbit(&file)?;

        let declared: Vec<String> = file.materials.keys().cloned().collect();
        let mut material_names = declared.clone();
        let mut materials = Vec::new();
        let mut textures = Vec::new();
        let mut tile_sizes = BTreeMap::new(); // material → texture tile size, for room UVs
        for (mname, m) in &file.materials {
            let field = format!("materials.{mname}");
            if let MaterialFile::Diffuse {
                texture: Some(t), ..
            } = m
            {
                tile_sizes.insert(mname.clone(), t.tile_size);
            }
            materials.push(self.material(&field, mname, m, &mut textures)?);
        }
        // Objects refer to declared materials; the lights' emissive ones come after them.
        let lookup = |field: &str, wanted: &str| -> Result<usize, SceneError> {
            declared.iter().position(|k| k == wanted).ok_or_else(|| {
                self.err(
                    field,
                    format!(
                        "unknown material \"{wanted}\" (known: {})",
                        declared.join(", ")
                    ),
                )
            })
        };

        // Room surfaces.
        let r = &file.room;
        let (min, max) = (self.vec3("room.min", r.min)?, self.vec3("room.max", r.max)?);
        if min.cmpge(max).any() {
            return Err(self.err(
                "room",
                format!("max {max:?} must exceed min {min:?} on every axis"),
            ));
        }
        let mut objects = Vec::new();
        let tile = |m: &str| tile_sizes.get(m).copied().unwrap_or(1.0);
        for (oname, mname, mesh) in [
            ("floor", &r.floor, room::floor(min, max, tile(&r.floor))),
            ("walls", &r.walls, room::walls(min, max, tile(&r.walls))),
            (
                "ceiling",
                &r.ceiling,
                room::ceiling(min, max, tile(&r.ceiling)),
            ),
        ] {
            objects.push(Object {
                name: oname.to_owned(),
                material: lookup(&format!("room.{oname}"), mname)?,
                mesh,
                em: None,
            });
        }

        // Lights: each also an object with its own emissive material, so rasterisers draw it.
        let mut lights = Vec::new();
        for (i, l) in file.lights.iter().enumerate() {
            let field = |f: &str| format!("lights[{i}].{f}");
            let light = AreaLight {
                name: l.name.clone(),
                center: self.vec3(&field("center"), l.center)?,
                edge_u: self.vec3(&field("edge_u"), l.edge_u)?,
                edge_v: self.vec3(&field("edge_v"), l.edge_v)?,
                radiance: self.vec3_in(&field("radiance"), l.radiance, 0.0, f32::MAX)?,
            };
            let scale = light.edge_u.length() * light.edge_v.length();
            if !(light.area() > 1e-6 * scale && light.area() > 1e-12) {
                return Err(self.err(
                    field("edge_u"),
                    "light has zero area (expected two non-parallel, non-zero edges)",
                ));
            }
            if light.center.cmplt(min).any() || light.center.cmpgt(max).any() {
                return Err(self.err(field("center"), "light centre is outside the room"));
            }
            if material_names.contains(&l.name) {
                return Err(self.err(
                    field("name"),
                    format!("\"{}\" is also a material name; light names name their own emissive material", l.name),
                ));
            }
            material_names.push(l.name.clone());
            materials.push(Material::Emissive {
                radiance: light.radiance,
            });
            objects.push(Object {
                name: l.name.clone(),
                mesh: light_mesh(&light),
                material: materials.len() - 1,
                em: None,
            });
            lights.push(light);
        }

        for (i, o) in file.objects.iter().enumerate() {
            objects.push(self.object(i, o, &lookup)?);
        }
        for (i, o) in objects.iter().enumerate() {
            if objects[..i].iter().any(|p| p.name == o.name) {
                return Err(self.err(
                    "objects",
                    format!("object name \"{}\" used twice (room surfaces are floor, walls, ceiling; lights are objects too)", o.name),
                ));
            }
        }

        Ok(Scene {
            name,
            source: self.path.to_owned(),
            camera,
            orbit,
            lights,
            materials,
            material_names,
            objects,
            textures,
        })
    }

    fn camera(&self, file: &SceneFile) -> Result<Camera, SceneError> {
        let c = &file.camera;
        let fov = self.finite("camera.fov_y_deg", c.fov_y_deg)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.err("camera.fov_y_deg", format!("{fov} outside (0, 180)")));
        }
        let near = self.positive("camera.near", c.near)?;
        let far = self.positive("camera.far", c.far)?;
        if far <= near {
            return Err(self.err("camera.far", format!("{far} must exceed near ({near})")));
        }
        Ok(Camera {
            fov_y_deg: fov,
            near,
            far,
        })
    }

    fn orbit(&self, file: &SceneFile) -> Result<Orbit, SceneError> {
        let o = &file.orbit;
        if o.samples == 0 {
            return Err(self.err("orbit.samples", "0 (expected at least 1)"));
        }
        Ok(Orbit {
            center: self.vec3("orbit.center", o.center)?,
            radius: self.positive("orbit.radius", o.radius)?,
            height: self.finite("orbit.height", o.height)?,
            start_deg: self.finite("orbit.start_deg", o.start_deg)?,
            step_deg: self.finite("orbit.step_deg", o.step_deg)?,
            samples: o.samples,
        })
    }

    fn material(
        &self,
        field: &str,
        name: &str,
        m: &MaterialFile,
        textures: &mut Vec<Texture>,
    ) -> Result<Material, SceneError> {
        let f = |k: &str| format!("{field}.{k}");
        Ok(match m {
            MaterialFile::Diffuse { albedo, texture } => Material::Diffuse {
                albedo: self.vec3_in(&f("albedo"), *albedo, 0.0, 1.0)?,
                texture: match texture {
                    Some(t) => {
                        textures.push(self.texture(&f("texture"), name, t)?);
                        Some(textures.len() - 1)
                    }
                    None => None,
                },
            },
            MaterialFile::Mirror { f0 } => Material::Mirror {
                f0: self.vec3_in(&f("f0"), *f0, 0.0, 1.0)?,
            },
            MaterialFile::Glossy { f0, roughness } => {
                let r = self.finite(&f("roughness"), *roughness)?;
                if !(r > 0.0 && r <= 1.0) {
                    return Err(self.err(f("roughness"), format!("{r} outside (0, 1]")));
                }
                Material::Glossy {
                    f0: self.vec3_in(&f("f0"), *f0, 0.0, 1.0)?,
                    roughness: r,
                }
            }
            MaterialFile::Glass { ior, absorption } => {
                let ior = self.finite(&f("ior"), *ior)?;
                if ior < 1.0 {
                    return Err(self.err(f("ior"), format!("{ior} below 1")));
                }
                Material::Glass {
                    ior,
                    absorption: self.vec3_in(&f("absorption"), *absorption, 0.0, f32::MAX)?,
                }
            }
            MaterialFile::Emissive { radiance } => Material::Emissive {
                radiance: self.vec3_in(&f("radiance"), *radiance, 0.0, f32::MAX)?,
            },
        })
    }

    fn texture(&self, field: &str, name: &str, t: &TextureFile) -> Result<Texture, SceneError> {
        let f = |k: &str| format!("{field}.{k}");
        let colors = [
            self.vec3_in(&f("colors[0]"), t.colors[0], 0.0, 1.0)?,
            self.vec3_in(&f("colors[1]"), t.colors[1], 0.0, 1.0)?,
        ];
        self.positive(&f("tile_size"), t.tile_size)?;
        let w = self.finite(&f("line_width"), t.line_width)?;
        if !(0.0..0.25).contains(&w) {
            return Err(self.err(f("line_width"), format!("{w} outside [0, 0.25) of a tile")));
        }
        if !(1..=MAX_TEXTURE_RESOLUTION).contains(&t.resolution) {
            return Err(self.err(
                f("resolution"),
                format!("{} outside 1..={MAX_TEXTURE_RESOLUTION}", t.resolution),
            ));
        }
        Ok(Texture::bake(name, t.pattern, colors, w, t.resolution))
    }

    fn object(
        &self,
        i: usize,
        o: &ObjectFile,
        lookup: &dyn Fn(&str, &str) -> Result<usize, SceneError>,
    ) -> Result<Object, SceneError> {
        let f = |k: &str| format!("objects[{i}].{k}");
        if o.name.trim().is_empty() {
            return Err(self.err(f("name"), "empty (expected a unique object name)"));
        }
        let material = lookup(&f("material"), &o.material)?;
        let mut mesh = self.mesh(&f("mesh"), &o.mesh)?;

        let t = &o.transform;
        let translate = self.vec3(&f("transform.translate"), t.translate)?;
        let scale = self.positive(&f("transform.scale"), t.scale)?;
        let angle = self.finite(&f("transform.rotate_y_deg"), t.rotate_y_deg)?;
        mesh.transform(&Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            Quat::from_rotation_y(angle.to_radians()),
            translate,
        ));

        let em = match &o.em {
            None => None,
            Some(em) => {
                if !(em.resolution.is_power_of_two() && em.resolution <= MAX_EM_RESOLUTION) {
                    return Err(self.err(
                        f("em.resolution"),
                        format!(
                            "{} is not a power of two in 1..={MAX_EM_RESOLUTION}",
                            em.resolution
                        ),
                    ));
                }
                if em.layers.is_empty() {
                    return Err(self.err(
                        f("em.layers"),
                        "empty (expected \"distant\" and/or \"local\")",
                    ));
                }
                if em.layers.len() == 2 && em.layers[0] == em.layers[1] || em.layers.len() > 2 {
                    return Err(
                        self.err(f("em.layers"), format!("{:?} repeats a layer", em.layers))
                    );
                }
                Some(EmSettings {
                    resolution: em.resolution,
                    layers: em.layers.clone(),
                })
            }
        };
        Ok(Object {
            name: o.name.clone(),
            mesh,
            material,
            em,
        })
    }

    fn mesh(&self, field: &str, m: &MeshFile) -> Result<Mesh, SceneError> {
        let nested = |source: SceneError| SceneError::Nested {
            path: self.path.to_owned(),
            field: field.to_owned(),
            source: Box::new(source),
        };
        let obj_path: PathBuf = match (&m.generator, &m.obj) {
            (Some(g), None) => {
                if g != "newell_teapot" {
                    return Err(self.err(
                        format!("{field}.generator"),
                        format!("unknown generator \"{g}\" (known: newell_teapot)"),
                    ));
                }
                let segments = m.segments.unwrap_or(DEFAULT_SEGMENTS);
                if !(1..=MAX_SEGMENTS).contains(&segments) {
                    return Err(self.err(
                        format!("{field}.segments"),
                        format!("{segments} outside 1..={MAX_SEGMENTS}"),
                    ));
                }
                let part = m.part.unwrap_or(TeapotPart::Whole);
                teapot::cached_obj(segments, part, self.cache_dir).map_err(nested)?
            }
            (None, Some(obj)) => {
                if m.segments.is_some() || m.part.is_some() {
                    return Err(self.err(
                        field,
                        "`segments` and `part` belong to a generator, not to `obj`",
                    ));
                }
                self.path.parent().unwrap_or(Path::new(".")).join(obj)
            }
            _ => {
                return Err(self.err(
                    field,
                    "expected exactly one of `generator = \"newell_teapot\"` or `obj = \"path.obj\"`",
                ));
            }
        };
        load_obj(&obj_path).map_err(nested)
    }
}

/// The light's rectangle as two triangles facing its emitting side.
fn light_mesh(l: &AreaLight) -> Mesh {
    let c = l.corners();
    let uv = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    Mesh {
        positions: c.to_vec(),
        normals: vec![l.normal(); 4],
        uvs: uv.iter().map(|&t| glam::Vec2::from_array(t)).collect(),
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}
