//! The scene's compiled maps, defined once: their kinds, which ones a
//! scene has (in container order), and where every compiled file lives
//! under a run's output folder.

use inference::scene::{EmLayer, Material, Object, Scene};
use inference::solve::layout::{TextureLayout, TextureShape};
use std::path::{Path, PathBuf};

/// One kind of inferred map of a reflector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MapLayer {
    /// The distant layer: an EM on the room's box.
    Distant,
    /// The local layer: premultiplied RGBA on the reflector's ellipsoid.
    Local,
    /// The whole specular appearance on one sphere-at-infinity EM.
    Sphere,
    /// A parameterized texture map on the reflector's atlas.
    Ptm,
}

/// The smallest PTM edge: the atlas needs room for its charts (at 16² the
/// tiny test teapot's 52 charts get 9 texel centres, at 64² 774).
pub const PTM_MIN_EDGE: u32 = 64;

/// The edge of a PTM beside `resolution`² EMs: the same, at least
/// [`PTM_MIN_EDGE`].
pub fn ptm_edge(resolution: u32) -> u32 {
    resolution.max(PTM_MIN_EDGE)
}

impl MapLayer {
    /// The map's file name part (`<object>.<part>.exr`).
    pub fn file_part(self) -> &'static str {
        match self {
            MapLayer::Distant => "specular_distant",
            MapLayer::Local => "specular_local",
            MapLayer::Sphere => "specular_sphere",
            MapLayer::Ptm => "ptm",
        }
    }
    pub fn channels(self) -> usize {
        match self {
            MapLayer::Local => 4,
            _ => 3,
        }
    }
    pub fn shape(self, resolution: u32) -> TextureShape {
        match self {
            MapLayer::Ptm => TextureShape::Tex2D {
                width: ptm_edge(resolution),
                height: ptm_edge(resolution),
            },
            _ => TextureShape::Cube { size: resolution },
        }
    }
    /// The full MIP chain of a `resolution` map.
    pub fn layout(self, resolution: u32) -> TextureLayout {
        TextureLayout::full_chain(self.shape(resolution))
    }
    pub fn from_em(layer: EmLayer) -> Self {
        match layer {
            EmLayer::Distant => MapLayer::Distant,
            EmLayer::Local => MapLayer::Local,
        }
    }
}

/// One parameterized map of the scene: which object and layer, its size.
#[derive(Clone, Debug, PartialEq)]
pub struct MapSpec {
    pub object: String,
    pub layer: MapLayer,
    pub resolution: u32,
}

impl MapSpec {
    /// `<object>.<layer>`, the map's name in files and reports.
    pub fn name(&self) -> String {
        format!("{}.{}", self.object, self.layer.file_part())
    }
    pub fn layout(&self) -> TextureLayout {
        self.layer.layout(self.resolution)
    }
}

/// Whether `object` reflects (and so may carry parameterized maps).
pub fn reflective(scene: &Scene, object: &Object) -> bool {
    matches!(
        scene.materials.get(object.material),
        Some(Material::Mirror { .. } | Material::Glossy { .. })
    )
}

/// The maps compiled for the scene, in container order: per reflector
/// with `[objects.em]`, its EM layers, then its PTM. (Sphere EMs are
/// inferred on request, in their own container: [`MapSet::Sphere`].)
pub fn map_specs(scene: &Scene) -> Vec<MapSpec> {
    MapSet::Scene.specs(scene)
}

/// The maps one container holds: the scene's own, or the sphere-PEM
/// baseline's, compiled only when asked for and compressed at the same
/// ratio (so `engine eval` ranks the methods at equal compression).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapSet {
    /// Per reflector its EM layers, then its PTM: `<scene>.ptxc`.
    Scene,
    /// Per reflector its sphere EM: `<scene>.sphere.ptxc`.
    Sphere,
}

impl MapSet {
    /// The set playing `layers` needs.
    pub fn of(layers: &[MapLayer]) -> Self {
        if layers.contains(&MapLayer::Sphere) {
            MapSet::Sphere
        } else {
            MapSet::Scene
        }
    }

    /// The set's maps, in container order.
    pub fn specs(self, scene: &Scene) -> Vec<MapSpec> {
        let mut specs = Vec::new();
        for o in scene.objects.iter().filter(|o| reflective(scene, o)) {
            let Some(em) = o.em.as_ref() else { continue };
            let spec = |layer| MapSpec {
                object: o.name.clone(),
                layer,
                resolution: em.resolution,
            };
            match self {
                MapSet::Scene => {
                    specs.extend(em.layers.iter().map(|&l| spec(MapLayer::from_em(l))));
                    specs.push(spec(MapLayer::Ptm));
                }
                MapSet::Sphere => specs.push(spec(MapLayer::Sphere)),
            }
        }
        specs
    }
}

/// Where a scene's compiled files live, under one output folder:
/// `trace/sample_KKKK.exr`, `infer/sample_KKKK/<object>.<layer>.exr` and
/// the container `<scene>.ptxc`.
#[derive(Clone, Debug, PartialEq)]
pub struct DataDirs {
    pub trace: PathBuf,
    pub infer: PathBuf,
    pub container: PathBuf,
}

impl DataDirs {
    pub fn under(out: &Path, scene: &Scene) -> Self {
        Self {
            trace: out.join("trace"),
            infer: out.join("infer"),
            container: out.join(format!("{}.ptxc", scene.name)),
        }
    }

    /// The container of `set`: `<scene>.ptxc` or `<scene>.sphere.ptxc`.
    pub fn container_of(&self, set: MapSet) -> PathBuf {
        match set {
            MapSet::Scene => self.container.clone(),
            MapSet::Sphere => self.container.with_extension("sphere.ptxc"),
        }
    }
}

/// `sample_KKKK`: the stem of sample `k`'s files.
pub fn sample_name(k: u32) -> String {
    format!("sample_{k:04}")
}

/// `<trace>/sample_KKKK`: the stem of sample `k`'s traced image.
pub fn traced_stem(trace_dir: &Path, k: u32) -> PathBuf {
    trace_dir.join(sample_name(k))
}

/// `<trace>/view_az±A_el±E`: the stem of a traced view off the samples
/// (azimuth and elevation above the orbit plane, degrees).
pub fn view_stem(trace_dir: &Path, azimuth_deg: f32, elevation_deg: f32) -> PathBuf {
    trace_dir.join(format!("view_az{azimuth_deg:+.3}_el{elevation_deg:+.3}"))
}

/// `<infer>/sample_KKKK`: the folder of sample `k`'s inferred maps.
pub fn sample_dir(infer_dir: &Path, k: u32) -> PathBuf {
    infer_dir.join(sample_name(k))
}

/// `<infer>/sample_KKKK/<object>.<layer>.exr`.
pub fn map_path(infer_dir: &Path, k: u32, object: &str, layer: MapLayer) -> PathBuf {
    sample_dir(infer_dir, k).join(format!("{object}.{}.exr", layer.file_part()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_teapot_has_its_layers_then_its_ptm() {
        let scene = Scene::load("teapot").expect("teapot");
        let names: Vec<String> = map_specs(&scene).iter().map(MapSpec::name).collect();
        assert_eq!(
            names,
            [
                "teapot.specular_distant",
                "teapot.specular_local",
                "teapot.ptm"
            ]
        );
        let p = map_path(Path::new("o/infer"), 7, "teapot", MapLayer::Local);
        assert_eq!(
            p,
            Path::new("o/infer/sample_0007/teapot.specular_local.exr")
        );
        assert_eq!(MapLayer::Local.channels(), 4);
        let sphere: Vec<String> = MapSet::Sphere
            .specs(&scene)
            .iter()
            .map(MapSpec::name)
            .collect();
        assert_eq!(sphere, ["teapot.specular_sphere"]);
        let dirs = DataDirs::under(Path::new("o"), &scene);
        assert_eq!(
            dirs.container_of(MapSet::Sphere),
            Path::new("o/teapot.sphere.ptxc")
        );
        assert_eq!(MapSet::of(&[MapLayer::Sphere]), MapSet::Sphere);
        assert_eq!(
            MapSet::of(&[MapLayer::Distant, MapLayer::Local]),
            MapSet::Scene
        );
        assert_eq!(MapLayer::Ptm.layout(16).faces(), 1);
    }
}
