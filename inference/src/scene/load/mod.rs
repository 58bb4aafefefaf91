//! From a parsed scene file to a validated `Scene`: every check names the file and field.

mod check;
mod glass;
mod lights;
mod materials;
mod objects;

use std::path::Path;

use glam::Vec3;

use super::camera::{Camera, Orbit};
use super::error::SceneError;
use super::file::{OrbitFile, RoomFile, SceneFile};
use super::light::AreaLight;
use super::material::Material;
use super::{Object, Origin, Scene, room};
use materials::Materials;

/// Validation context: the scene file (for relative mesh paths and a
/// nameless scene's name) and what messages call the scene.
pub struct Loader<'a> {
    pub path: &'a Path,
    pub origin: &'a Origin,
}

/// Most viewpoint samples a scene may ask for (a 64 × 64 grid).
pub const MAX_SAMPLES: u32 = 4096;
/// Elevation rings of a 2D viewpoint space.
pub const MAX_RINGS: u32 = 16;
/// The top ring's elevation above the orbit (the eye stays off the pole).
pub const MAX_RING_DEG: f32 = 80.0;

/// What the room, the lights and the file's objects add up to, in order.
struct SceneParts {
    /// Declared materials' names, then one per light (the light's name).
    material_names: Vec<String>,
    materials: Vec<Material>,
    objects: Vec<Object>,
    lights: Vec<AreaLight>,
}

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
        // Objects refer to declared materials only, not to the lights' ones.
        let lookup =
            |field: &str, wanted: &str| self.material_index(&declared.names, field, wanted);

        let room = self.room_box(&file.room)?;
        self.check_eyes_in_room(&orbit, room)?;
        let mut parts = SceneParts {
            material_names: declared.names.clone(),
            materials: declared.materials.clone(),
            objects: self.room_objects(&file.room, room, &declared, &lookup)?,
            lights: Vec::new(),
        };
        for (i, l) in file.lights.iter().enumerate() {
            self.add_light(i, l, room, &mut parts)?;
        }
        for (i, o) in file.objects.iter().enumerate() {
            parts
                .objects
                .push(self.object(i, o, &lookup, &declared.materials)?);
        }
        self.check_unique_names(&parts.objects)?;
        self.check_one_glass(&file.objects)?;
        let (directional_lights, point_lights) = self.extra_lights(&file, room)?;

        Ok(Scene {
            name,
            source: self.path.to_owned(),
            origin: self.origin.clone(),
            camera,
            orbit,
            lights: parts.lights,
            directional_lights,
            point_lights,
            materials: parts.materials,
            material_names: parts.material_names,
            objects: parts.objects,
            textures: declared.textures,
        })
    }

    /// Index of material `wanted` among `known`; `field` names the reference.
    fn material_index(
        &self,
        known: &[String],
        field: &str,
        wanted: &str,
    ) -> Result<usize, SceneError> {
        known.iter().position(|k| k == wanted).ok_or_else(|| {
            let list = known.join(", ");
            self.err(
                field,
                format!("unknown material \"{wanted}\" (known: {list})"),
            )
        })
    }

    /// Floor, walls and ceiling of the room box `(min, max)`, with their
    /// materials' tile sizes for the UVs.
    fn room_objects(
        &self,
        r: &RoomFile,
        (min, max): (Vec3, Vec3),
        declared: &Materials,
        lookup: &dyn Fn(&str, &str) -> Result<usize, SceneError>,
    ) -> Result<Vec<Object>, SceneError> {
        let tile = |m: &str| declared.tile_sizes.get(m).copied().unwrap_or(1.0);
        let mut objects = Vec::new();
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
                trace_mesh: None,
                material,
                em: None,
                glass: None,
            });
        }
        Ok(objects)
    }

    fn check_unique_names(&self, objects: &[Object]) -> Result<(), SceneError> {
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
        Ok(())
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
        let lines = self.azimuth_lines(o)?;
        let rings = self.ring_layout(o)?;
        let every = o.ring_line_every.unwrap_or(1);
        if !(1..=MAX_SAMPLES).contains(&every) {
            return Err(self.err(
                "orbit.ring_line_every",
                format!("{every} (expected 1 to {MAX_SAMPLES} lines)"),
            ));
        }
        let layout = crate::scene::ring_lines::RingLines {
            lines: lines.samples,
            every,
        };
        if layout.count(rings.rings) > MAX_SAMPLES {
            let field = match rings.elevations {
                Some(_) => "orbit.ring_elevations_deg",
                None => "orbit.rings",
            };
            return Err(self.err(
                field,
                format!(
                    "{} (expected samples × rings at most {MAX_SAMPLES})",
                    rings.rings
                ),
            ));
        }
        Ok(Orbit {
            center: self.vec3("orbit.center", o.center)?,
            radius: self.positive("orbit.radius", o.radius)?,
            height: self.finite("orbit.height", o.height)?,
            start_deg: lines.start_deg,
            step_deg: lines.step_deg,
            samples: lines.samples,
            rings: rings.rings,
            ring_step_deg: rings.step_deg,
            azimuths: lines.azimuths,
            elevations: rings.elevations,
            ring_line_every: every,
        })
    }

    /// The orbit's rings: even (`rings`, `ring_step_deg`) or explicit
    /// (`ring_elevations_deg`: finite, increasing from 0), never both.
    fn ring_layout(&self, o: &OrbitFile) -> Result<RingLayout, SceneError> {
        let Some(list) = &o.ring_elevations_deg else {
            let rings = o.rings.unwrap_or(1);
            if !(1..=MAX_RINGS).contains(&rings) {
                return Err(self.err(
                    "orbit.rings",
                    format!("{rings} (expected 1 to {MAX_RINGS})"),
                ));
            }
            let step = o.ring_step_deg.unwrap_or(10.0);
            let top = (rings - 1) as f32 * step;
            // A step given for one ring is unused, but still has to be a step.
            let checked = rings > 1 || o.ring_step_deg.is_some();
            if checked && !(step > 0.0 && top <= MAX_RING_DEG) {
                return Err(self.err(
                    "orbit.ring_step_deg",
                    format!(
                        "{step} (expected a finite step above 0, the top ring at most {MAX_RING_DEG}° above the orbit)"
                    ),
                ));
            }
            return Ok(RingLayout {
                rings,
                step_deg: step,
                elevations: None,
            });
        };
        if o.rings.is_some() || o.ring_step_deg.is_some() {
            return Err(self.err(
                "orbit.ring_elevations_deg",
                "given with rings or ring_step_deg (expected either the explicit rings or the \
                 even ones)"
                    .to_string(),
            ));
        }
        let n = list.len() as u32;
        let increasing = list.windows(2).all(|w| w[0] < w[1]);
        let in_range = list.first() == Some(&0.0) && list.iter().all(|e| *e <= MAX_RING_DEG);
        if !(1..=MAX_RINGS).contains(&n)
            || !list.iter().all(|e| e.is_finite())
            || !increasing
            || !in_range
        {
            return Err(self.err(
                "orbit.ring_elevations_deg",
                format!(
                    "{list:?} (expected 1 to {MAX_RINGS} finite elevations in degrees, the first \
                     0, each above the one before, the last at most {MAX_RING_DEG})"
                ),
            ));
        }
        Ok(RingLayout {
            rings: n,
            step_deg: if n > 1 {
                list[list.len() - 1] / (n - 1) as f32
            } else {
                10.0
            },
            elevations: Some(list.clone()),
        })
    }

    /// The orbit's azimuth lines: even (`start_deg`, `step_deg`, `samples`)
    /// or explicit (`azimuths_deg`: finite, increasing), never both.
    fn azimuth_lines(&self, o: &OrbitFile) -> Result<AzimuthLines, SceneError> {
        let Some(list) = &o.azimuths_deg else {
            let samples = o.samples.unwrap_or(100);
            if !(1..=MAX_SAMPLES).contains(&samples) {
                return Err(self.err(
                    "orbit.samples",
                    format!("{samples} (expected 1 to {MAX_SAMPLES})"),
                ));
            }
            let step = self.finite("orbit.step_deg", o.step_deg.unwrap_or(1.0))?;
            // Lines increase and stay within one turn (the blend brackets a
            // view between increasing azimuths); one sample needs no step.
            let span = (samples - 1) as f32 * step;
            if samples > 1 && !(step > 0.0 && span < 360.0) {
                return Err(self.err(
                    "orbit.step_deg",
                    format!(
                        "{step} with {samples} samples (expected a step above 0 whose lines \
                         span less than 360°, here {span}°)"
                    ),
                ));
            }
            return Ok(AzimuthLines {
                start_deg: self.finite("orbit.start_deg", o.start_deg.unwrap_or(0.0))?,
                step_deg: step,
                samples,
                azimuths: None,
            });
        };
        if o.samples.is_some() || o.start_deg.is_some() || o.step_deg.is_some() {
            return Err(self.err(
                "orbit.azimuths_deg",
                "given with start_deg, step_deg or samples (expected either the explicit lines \
                 or the even ones)"
                    .to_string(),
            ));
        }
        let increasing = list.windows(2).all(|w| w[0] < w[1]);
        let n = list.len() as u32;
        if !(1..=MAX_SAMPLES).contains(&n) || !list.iter().all(|a| a.is_finite()) || !increasing {
            return Err(self.err(
                "orbit.azimuths_deg",
                format!(
                    "{} lines (expected 1 to {MAX_SAMPLES} finite azimuths in degrees, each \
                     above the one before)",
                    list.len()
                ),
            ));
        }
        let (first, last) = (list[0], list[list.len() - 1]);
        if last - first >= 360.0 {
            return Err(self.err(
                "orbit.azimuths_deg",
                format!("{first}° to {last}° (expected lines spanning less than 360°: one turn)"),
            ));
        }
        Ok(AzimuthLines {
            start_deg: first,
            step_deg: if n > 1 {
                (last - first) / (n - 1) as f32
            } else {
                1.0
            },
            samples: n,
            azimuths: Some(list.clone()),
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
                format!(
                    "max {} must exceed min {} on every axis",
                    check::toml3(max),
                    check::toml3(min)
                ),
            ));
        }
        Ok((min, max))
    }
}

/// An orbit's rings as the loader found them.
struct RingLayout {
    rings: u32,
    step_deg: f32,
    elevations: Option<Vec<f32>>,
}

/// An orbit's azimuth lines as the loader found them.
struct AzimuthLines {
    start_deg: f32,
    step_deg: f32,
    samples: u32,
    azimuths: Option<Vec<f32>>,
}
