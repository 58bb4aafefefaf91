//! From a parsed scene file to a validated `Scene`: every check names the file and field.

mod check;
mod materials;
mod objects;

use std::path::Path;

use glam::Vec3;

use super::camera::{Camera, Orbit};
use super::error::SceneError;
use super::file::{LightFile, RoomFile, SceneFile};
use super::light::AreaLight;
use super::material::Material;
use super::{Object, Scene, room};

/// Validation context: the scene file (for messages and relative mesh paths).
pub struct Loader<'a> {
    pub path: &'a Path,
}

/// Most viewpoint samples a scene may ask for (a 64 × 64 grid).
pub const MAX_SAMPLES: u32 = 4096;

impl Loader<'_> {
    /// Objects come out as: floor, walls, ceiling, one per light, then the file's objects.
    /// Materials: the declared ones sorted by name, then one emissive per light.
    pub fn build(&self, file: SceneFile) -> Result<Scene, SceneError> {
        let name = file.name.clone().unwrap_or_else(|| {
            let stem = self.path.file_stem().unwrap_or_default();
            stem.to_string_lossy().into_owned()
        });
        self.check_name(&name)?;
        let camera = self.camera(&file)?;
        let orbit = self.orbit(&file)?;
        let declared = self.materials(&file.materials)?;

        // Objects refer to declared materials only.
        let lookup = |field: &str, wanted: &str| -> Result<usize, SceneError> {
            let known = &declared.names;
            known.iter().position(|k| k == wanted).ok_or_else(|| {
                let list = known.join(", ");
                self.err(
                    field,
                    format!("unknown material \"{wanted}\" (known: {list})"),
                )
            })
        };

        let (min, max) = self.room_box(&file.room)?;
        let mut objects = Vec::new();
        let tile = |m: &str| declared.tile_sizes.get(m).copied().unwrap_or(1.0);
        let r = &file.room;
        for (oname, mname, mesh) in [
            ("floor", &r.floor, room::floor(min, max, tile(&r.floor))),
            ("walls", &r.walls, room::walls(min, max, tile(&r.walls))),
            (
                "ceiling",
                &r.ceiling,
                room::ceiling(min, max, tile(&r.ceiling)),
            ),
        ] {
            let material = lookup(&format!("room.{oname}"), mname)?;
            objects.push(Object {
                name: oname.to_owned(),
                mesh,
                material,
                em: None,
            });
        }

        // Each light is also an object with its own emissive material, so rasterisers draw it.
        let mut material_names = declared.names.clone();
        let mut materials = declared.materials.clone();
        let mut lights = Vec::new();
        for (i, l) in file.lights.iter().enumerate() {
            let light = self.light(i, l, (min, max))?;
            if material_names.contains(&light.name) {
                return Err(self.err(
                    format!("lights[{i}].name"),
                    format!(
                        "\"{}\" is also a material name (a light's name names its emissive material)",
                        light.name
                    ),
                ));
            }
            material_names.push(light.name.clone());
            materials.push(Material::Emissive {
                radiance: light.radiance,
            });
            objects.push(Object {
                name: light.name.clone(),
                mesh: light.mesh(),
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
                    format!(
                        "object name \"{}\" used twice (floor, walls, ceiling and lights are objects too)",
                        o.name
                    ),
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
            textures: declared.textures,
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
        if !(1..=MAX_SAMPLES).contains(&o.samples) {
            return Err(self.err(
                "orbit.samples",
                format!("{} (expected 1 to {MAX_SAMPLES})", o.samples),
            ));
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

    /// The scene's name names its output folder and files: a plain name,
    /// never a path.
    fn check_name(&self, name: &str) -> Result<(), SceneError> {
        let plain = name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
        if name.is_empty() || name.len() > 64 || !plain || name.starts_with('.') {
            return Err(self.err(
                "name",
                format!(
                    "{name:?} (expected 1 to 64 letters, digits, '_', '-' or '.', not starting with '.': it names the output folder)"
                ),
            ));
        }
        Ok(())
    }

    fn room_box(&self, r: &RoomFile) -> Result<(Vec3, Vec3), SceneError> {
        let (min, max) = (self.vec3("room.min", r.min)?, self.vec3("room.max", r.max)?);
        if min.cmpge(max).any() {
            return Err(self.err(
                "room",
                format!("max {max:?} must exceed min {min:?} on every axis"),
            ));
        }
        Ok((min, max))
    }

    fn light(
        &self,
        i: usize,
        l: &LightFile,
        (min, max): (Vec3, Vec3),
    ) -> Result<AreaLight, SceneError> {
        let field = |f: &str| format!("lights[{i}].{f}");
        let light = AreaLight {
            name: l.name.clone(),
            center: self.vec3(&field("center"), l.center)?,
            edge_u: self.vec3(&field("edge_u"), l.edge_u)?,
            edge_v: self.vec3(&field("edge_v"), l.edge_v)?,
            radiance: self.vec3_in(&field("radiance"), l.radiance, 0.0, f32::MAX)?,
        };
        if light.name.trim().is_empty() {
            return Err(self.err(field("name"), "empty (expected a unique light name)"));
        }
        // Relative test: parallel edges give a rounding-noise cross product.
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
        Ok(light)
    }
}
