//! Area lights. Each is also an object with its own emissive material, named
//! after the light, so rasterisers draw it.

use glam::Vec3;

use super::{Loader, SceneParts};
use crate::scene::Object;
use crate::scene::error::SceneError;
use crate::scene::file::{LightFile, SceneFile};
use crate::scene::light::{AreaLight, DirectionalLight, PointLight};
use crate::scene::material::Material;

impl Loader<'_> {
    /// Validates light `i` inside the room `(min, max)` and adds it to
    /// `parts` with its emissive material and object. Its name may not be a
    /// material's (declared or an earlier light's).
    pub(super) fn add_light(
        &self,
        i: usize,
        l: &LightFile,
        room: (Vec3, Vec3),
        parts: &mut SceneParts,
    ) -> Result<(), SceneError> {
        let light = self.light(i, l, room)?;
        if parts.material_names.contains(&light.name) {
            return Err(self.err(
                format!("lights[{i}].name"),
                format!(
                    "\"{}\" is also a material name (a light's name names its emissive material)",
                    light.name
                ),
            ));
        }
        parts.material_names.push(light.name.clone());
        parts.materials.push(Material::Emissive {
            radiance: light.radiance,
        });
        parts.objects.push(Object {
            name: light.name.clone(),
            mesh: light.mesh(),
            trace_mesh: None,
            material: parts.materials.len() - 1,
            em: None,
            glass: None,
        });
        parts.lights.push(light);
        Ok(())
    }

    /// Light `i` checked: finite vectors, a name, non-zero area, centre
    /// inside the room.
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

    /// The optional directional and point lights: named, finite, non-negative
    /// power, a non-zero direction (normalised), point lights inside the room.
    pub(super) fn extra_lights(
        &self,
        file: &SceneFile,
        (min, max): (Vec3, Vec3),
    ) -> Result<(Vec<DirectionalLight>, Vec<PointLight>), SceneError> {
        let named = |field: String, name: &str| {
            if name.trim().is_empty() {
                Err(self.err(field, "empty (expected a light name)"))
            } else {
                Ok(name.to_owned())
            }
        };
        let mut directional = Vec::new();
        for (i, l) in file.directional_lights.iter().enumerate() {
            let field = |f: &str| format!("directional_lights[{i}].{f}");
            let to_light = self.vec3(&field("to_light"), l.to_light)?;
            if to_light.length_squared() < 1e-12 {
                return Err(self.err(field("to_light"), "zero vector (expected a direction)"));
            }
            directional.push(DirectionalLight {
                name: named(field("name"), &l.name)?,
                to_light: to_light.normalize(),
                irradiance: self.vec3_in(&field("irradiance"), l.irradiance, 0.0, f32::MAX)?,
            });
        }
        let mut points = Vec::new();
        for (i, l) in file.point_lights.iter().enumerate() {
            let field = |f: &str| format!("point_lights[{i}].{f}");
            let position = self.vec3(&field("position"), l.position)?;
            if position.cmplt(min).any() || position.cmpgt(max).any() {
                return Err(self.err(field("position"), "point light is outside the room"));
            }
            points.push(PointLight {
                name: named(field("name"), &l.name)?,
                position,
                intensity: self.vec3_in(&field("intensity"), l.intensity, 0.0, f32::MAX)?,
            });
        }
        Ok((directional, points))
    }
}
