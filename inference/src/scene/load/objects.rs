//! Scene objects: mesh source (generator, OBJ or glTF file), transform, material, EM settings.

use std::path::Path;

use glam::{Affine3A, Quat, Vec3};

use super::Loader;
use crate::scene::Object;
use crate::scene::error::SceneError;
use crate::scene::file::{EmFile, MeshFile, ObjectFile};
use crate::scene::gltf::load_gltf;
use crate::scene::material::EmSettings;
use crate::scene::mesh::Mesh;
use crate::scene::obj::load_obj;
use crate::teapot::{self, DEFAULT_SEGMENTS, MAX_SEGMENTS, TeapotPart};

use crate::scene::material::{
    EM_RESOLUTIONS, LOCAL_BOUNDS, LOD_BIASES, NEIGHBOUR_ABOVE_DEGS, NEIGHBOUR_ABOVE_MAX,
    NEIGHBOUR_ABOVE_SPACINGS, NEIGHBOUR_ABOVE_WEIGHTS, NEIGHBOUR_DEGS, NEIGHBOUR_WEIGHTS,
};

/// The largest vertex coordinate a scene may place (metres): squares of
/// coordinates, as areas and cross products make, stay far inside f32.
const MAX_COORDINATE: f32 = 1e9;

impl Loader<'_> {
    pub(super) fn object(
        &self,
        i: usize,
        o: &ObjectFile,
        lookup: &dyn Fn(&str, &str) -> Result<usize, SceneError>,
        materials: &[crate::scene::Material],
    ) -> Result<Object, SceneError> {
        let f = |k: &str| format!("objects[{i}].{k}");
        if o.name.trim().is_empty() {
            return Err(self.err(f("name"), "empty (expected a unique object name)"));
        }
        let material = lookup(&f("material"), &o.material)?;
        let mut mesh = self.mesh(&f("mesh"), &o.mesh)?;
        let mut trace_mesh = self.trace_mesh(&f("mesh"), &o.mesh)?;

        let t = &o.transform;
        let translate = self.vec3(&f("transform.translate"), t.translate)?;
        let scale = self.positive(&f("transform.scale"), t.scale)?;
        let angle = self.finite(&f("transform.rotate_y_deg"), t.rotate_y_deg)?;
        let placement = Affine3A::from_scale_rotation_translation(
            Vec3::splat(scale),
            Quat::from_rotation_y(angle.to_radians()),
            translate,
        );
        mesh.transform(&placement);
        if let Some(m) = &mut trace_mesh {
            m.transform(&placement);
        }
        // Each number is finite, but their product may not be, nor the
        // edges, normals and areas built from it later.
        let placed = std::iter::once(&mesh).chain(&trace_mesh);
        let within = |p: &Vec3| p.is_finite() && p.abs().max_element() <= MAX_COORDINATE;
        if !placed.flat_map(|m| &m.positions).all(within) {
            return Err(self.err(
                f("transform"),
                format!(
                    "places a vertex beyond ±{MAX_COORDINATE:e} m (expected a scale and \
                     translation that keep every coordinate within it)"
                ),
            ));
        }

        let em = match &o.em {
            Some(em) => Some(self.em(&f("em"), em)?),
            None => None,
        };
        let glass = match &o.glass {
            Some(g) => Some(self.glass(&f("glass"), g, materials.get(material))?),
            None => None,
        };
        Ok(Object {
            name: o.name.clone(),
            mesh,
            trace_mesh,
            material,
            em,
            glass,
        })
    }

    fn mesh(&self, field: &str, m: &MeshFile) -> Result<Mesh, SceneError> {
        let nested = |source: SceneError| SceneError::Nested {
            scene: self.origin.clone(),
            field: field.to_owned(),
            cause: Box::new(source),
        };
        let (name, strict) = match (&m.generator, &m.obj, &m.file) {
            (Some(g), None, None) => {
                if g != "newell_teapot" {
                    return Err(self.err(
                        format!("{field}.generator"),
                        format!("unknown generator \"{g}\" (known: newell_teapot)"),
                    ));
                }
                return self.newell_teapot(field, "segments", m.segments, m.part);
            }
            (None, Some(obj), None) => (obj, false),
            (None, None, Some(file)) => (file, true),
            _ => {
                return Err(self.err(
                    field,
                    "expected exactly one of `generator = \"newell_teapot\"`, \
                     `file = \"path.obj|.gltf|.glb\"` or `obj = \"path.obj\"`",
                ));
            }
        };
        if m.segments.is_some() || m.trace_segments.is_some() || m.part.is_some() {
            return Err(self.err(
                field,
                "`segments`, `trace_segments` and `part` belong to a generator, not to a mesh file",
            ));
        }
        let path = self.path.parent().unwrap_or(Path::new(".")).join(name);
        // By extension; `obj` keeps reading anything else as OBJ, as it always did.
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("gltf" | "glb") => load_gltf(&path).map_err(nested),
            Some("obj") => load_obj(&path).map_err(nested),
            _ if !strict => load_obj(&path).map_err(nested),
            _ => Err(self.err(
                format!("{field}.file"),
                format!("\"{name}\": unknown mesh format (expected a .obj, .gltf or .glb file)"),
            )),
        }
    }
    /// The tracer's own tessellation of a generated mesh
    /// (`trace_segments`), when the scene asks for one; the mesh's other
    /// keys were checked by [`Loader::mesh`].
    fn trace_mesh(&self, field: &str, m: &MeshFile) -> Result<Option<Mesh>, SceneError> {
        m.trace_segments
            .map(|given| self.newell_teapot(field, "trace_segments", Some(given), m.part))
            .transpose()
    }

    /// Newell's teapot tessellated with `segments` (given under `key`,
    /// checked; [`DEFAULT_SEGMENTS`] when not given).
    fn newell_teapot(
        &self,
        field: &str,
        key: &str,
        segments: Option<u32>,
        part: Option<TeapotPart>,
    ) -> Result<Mesh, SceneError> {
        let segments = segments.unwrap_or(DEFAULT_SEGMENTS);
        if !(1..=MAX_SEGMENTS).contains(&segments) {
            return Err(self.err(
                format!("{field}.{key}"),
                format!("{segments} outside 1..={MAX_SEGMENTS}"),
            ));
        }
        let part = part.unwrap_or(TeapotPart::Whole);
        teapot::tessellate(segments, part)
            .map(|t| t.mesh)
            .map_err(|source| SceneError::Nested {
                scene: self.origin.clone(),
                field: field.to_owned(),
                cause: Box::new(source),
            })
    }

    fn em(&self, field: &str, em: &EmFile) -> Result<EmSettings, SceneError> {
        if !(em.resolution.is_power_of_two() && EM_RESOLUTIONS.contains(&em.resolution)) {
            return Err(self.err(
                format!("{field}.resolution"),
                format!(
                    "{} (expected a power of two from {} to {})",
                    em.resolution,
                    EM_RESOLUTIONS.start(),
                    EM_RESOLUTIONS.end()
                ),
            ));
        }
        if em.layers.is_empty() {
            return Err(self.err(
                format!("{field}.layers"),
                "empty (expected \"distant\" and/or \"local\")",
            ));
        }
        let repeats = em
            .layers
            .iter()
            .enumerate()
            .any(|(i, l)| em.layers[..i].contains(l));
        if repeats {
            return Err(self.err(
                format!("{field}.layers"),
                format!("{:?} repeats a layer", em.layers),
            ));
        }
        self.in_range(
            format!("{field}.lod_bias"),
            em.lod_bias,
            &LOD_BIASES,
            "levels",
        )?;
        self.in_range(
            format!("{field}.neighbour_weight"),
            em.neighbour_weight,
            &NEIGHBOUR_WEIGHTS,
            "a weight",
        )?;
        let bound = format!("{field}.local_bound");
        self.in_range(bound, em.local_bound, &LOCAL_BOUNDS, "a weight")?;
        if let Some(deg) = em.neighbour_deg {
            self.in_range(
                format!("{field}.neighbour_deg"),
                deg,
                &NEIGHBOUR_DEGS,
                "degrees either side of a sample",
            )?;
        }
        self.views_above(field, em)?;
        Ok(EmSettings {
            resolution: em.resolution,
            layers: em.layers.clone(),
            lod_bias: em.lod_bias,
            neighbour_weight: em.neighbour_weight,
            local_bound: em.local_bound,
            display_weight: em.display_weight,
            neighbour_deg: em.neighbour_deg,
            neighbour_above_deg: em.neighbour_above_deg.clone(),
            neighbour_above_spacing_deg: em.neighbour_above_spacing_deg,
            neighbour_above_weight: em.neighbour_above_weight,
        })
    }

    /// `neighbour_above_deg`: a few distinct, non-zero elevations in range,
    /// and stacking on (without it the views would be traced for nothing).
    fn views_above(&self, field: &str, em: &EmFile) -> Result<(), SceneError> {
        let above = &em.neighbour_above_deg;
        let name = format!("{field}.neighbour_above_deg");
        if let Some(d) = em.neighbour_above_spacing_deg {
            let spacing = format!("{field}.neighbour_above_spacing_deg");
            let what = "degrees between shared views above";
            self.in_range(spacing.clone(), d, &NEIGHBOUR_ABOVE_SPACINGS, what)?;
            if above.is_empty() {
                return Err(self.err(
                    spacing,
                    format!("{d} needs `neighbour_above_deg` (the elevations of the views)"),
                ));
            }
        }
        if let Some(w) = em.neighbour_above_weight {
            let weight = format!("{field}.neighbour_above_weight");
            self.in_range(weight.clone(), w, &NEIGHBOUR_ABOVE_WEIGHTS, "a weight")?;
            if above.is_empty() {
                return Err(self.err(
                    weight,
                    format!("{w} needs `neighbour_above_deg` (the elevations of the views)"),
                ));
            }
        }
        if above.is_empty() {
            return Ok(());
        }
        if above.len() > NEIGHBOUR_ABOVE_MAX {
            return Err(self.err(
                name,
                format!("{above:?} (expected at most {NEIGHBOUR_ABOVE_MAX} elevations)"),
            ));
        }
        for (i, &e) in above.iter().enumerate() {
            let what = "degrees above a sample, not 0";
            self.in_range(name.clone(), e, &NEIGHBOUR_ABOVE_DEGS, what)?;
            if e == 0.0 || above[..i].contains(&e) {
                return Err(self.err(
                    name,
                    format!("{above:?} (expected distinct elevations other than 0)"),
                ));
            }
        }
        if em.neighbour_weight <= 0.0 {
            return Err(self.err(
                name,
                format!("{above:?} needs `neighbour_weight` above 0 (the weight of stacked views)"),
            ));
        }
        Ok(())
    }
}
