//! Results other engines load: every sample's inferred maps as KTX 2.0
//! files (float32 RGBA, cube maps with all their inferred MIP levels), one
//! per sample and map, and a JSON sidecar (`maps.json`) with each
//! sample's viewpoint and each map's EM geometry (see [`sidecar`]).
//!
//! The maps are read as the encoder reads them (checked against their key
//! records) and written texel for texel as playback uploads them: a map
//! without alpha gets A = 1, the local layer stays premultiplied.

pub mod ktx2;
pub mod sidecar;

use crate::compile::encode::{MapsFor, map_keys};
use crate::compile::infer::jobs_for;
use crate::maps::{MapLayer, MapSet, MapSpec, map_path, map_specs};
use crate::util::files::{check_overwrite, claim_dir, write, write_json};
use anyhow::{Context, Result, bail};
use inference::infer::maps::parse_map;
use inference::scene::Scene;
use inference::scene::obj::write_obj;
use std::path::{Path, PathBuf};

/// The sidecar's file name inside the export folder.
pub const SIDECAR: &str = "maps.json";

/// One file written.
#[derive(Clone, Debug)]
pub struct ExportedFile {
    pub sample: u32,
    /// `<object>.<layer>`.
    pub map: String,
    pub path: PathBuf,
    pub bytes: u64,
}

/// What an export wrote.
#[derive(Clone, Debug)]
pub struct Exported {
    pub files: Vec<ExportedFile>,
    /// Each PTM's mesh on its atlas (OBJ).
    pub atlases: Vec<PathBuf>,
    pub sidecar: PathBuf,
}

impl Exported {
    /// A few lines for people: the folder, counts, one sample's files.
    pub fn summary(&self) -> String {
        let total: u64 = self.files.iter().map(|f| f.bytes).sum();
        let samples = self
            .files
            .iter()
            .map(|f| f.sample)
            .max()
            .map_or(0, |s| s + 1);
        let mut out = format!(
            "exported {} KTX2 files ({samples} samples, {total} bytes) and {}\n",
            self.files.len(),
            self.sidecar.display()
        );
        for a in &self.atlases {
            out += &format!("  PTM atlas mesh: {}\n", a.display());
        }
        for f in self.files.iter().filter(|f| f.sample == 0) {
            out += &format!(
                "  sample 0 {}: {} ({} bytes)\n",
                f.map,
                f.path.display(),
                f.bytes
            );
        }
        out
    }
}

/// `<object>.<layer>.sample_KKKK.ktx2`.
pub fn file_name(spec: &MapSpec, sample: u32) -> String {
    format!("{}.{}.ktx2", spec.name(), crate::maps::sample_name(sample))
}

/// Writes every sample's maps from `infer_dir` as KTX2 files into `out`
/// (claimed: made, empty or the engine's) and the sidecar beside them.
pub fn export_ktx2(scene: &Scene, infer_dir: &Path, out: &Path) -> Result<Exported> {
    // Every map there with its key record, checked before the folder is
    // claimed: a run that cannot export leaves nothing.
    map_keys(scene, MapSet::Scene, infer_dir, MapsFor::Export)?;
    let specs = map_specs(scene);
    let jobs = jobs_for(scene, None, false)?;
    claim_dir(out)?;
    let writer = format!("pem-engine {}", env!("CARGO_PKG_VERSION"));
    let mut files = Vec::new();
    for k in 0..scene.orbit.sample_count() {
        for spec in &specs {
            let texture = read_texture(infer_dir, k, spec, &writer)?;
            let bytes = ktx2::encode(&texture)
                .with_context(|| format!("{} of sample {k}: not a KTX2 texture", spec.name()))?;
            let path = out.join(file_name(spec, k));
            check_overwrite(&path)?;
            write(&path, &bytes)?;
            files.push(ExportedFile {
                sample: k,
                map: spec.name(),
                path,
                bytes: bytes.len() as u64,
            });
        }
    }
    let atlases = (specs.iter().filter(|s| s.layer == MapLayer::Ptm))
        .map(|spec| write_atlas(scene, spec, out))
        .collect::<Result<_>>()?;
    let sidecar = out.join(SIDECAR);
    check_overwrite(&sidecar)?;
    write_json(&sidecar, &sidecar::Sidecar::new(scene, &specs, &jobs))?;
    Ok(Exported {
        files,
        atlases,
        sidecar,
    })
}

/// `<object>.ptm_atlas.obj`: the mesh a PTM is drawn on (its atlas,
/// `inference::atlas`: vertices repeated where charts meet; `vt` as the
/// engine samples, v = 0 the texture's first row).
pub fn atlas_file_name(object: &str) -> String {
    format!("{object}.ptm_atlas.obj")
}

fn write_atlas(scene: &Scene, spec: &MapSpec, out: &Path) -> Result<PathBuf> {
    let Some(object) = scene.object(&spec.object) else {
        bail!("{}: no object {} in the scene", scene.origin, spec.object);
    };
    let edge = crate::maps::ptm_edge(spec.resolution);
    let mesh = inference::atlas::build(&object.mesh, edge).mesh(&object.mesh);
    let path = out.join(atlas_file_name(&spec.object));
    check_overwrite(&path)?;
    let header = format!(
        "{}'s PTM atlas ({edge}² texels), written by pem-engine {}",
        spec.object,
        env!("CARGO_PKG_VERSION")
    );
    write_obj(&path, &mesh, &header).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// Sample `k`'s map `spec` as an RGBA texture: checked against its key
/// record, parsed as every reader of maps does, missing alpha set to 1.
pub fn read_texture<'w>(
    infer_dir: &Path,
    k: u32,
    spec: &MapSpec,
    writer: &'w str,
) -> Result<ktx2::Texture<'w>> {
    let path = map_path(infer_dir, k, &spec.object, spec.layer);
    let bytes = inference::key::read_verified(&path).map_err(|why| {
        anyhow::anyhow!(
            "{why} (sample {k}'s {}: expected the maps `engine infer --all` or the main job \
             compiled into {})",
            spec.name(),
            infer_dir.display()
        )
    })?;
    let layout = spec.layout();
    let channels = spec.layer.channels();
    let map = parse_map(&bytes, &path, &layout, channels)?;
    let levels = (0..layout.levels())
        .map(|level| {
            let (w, h) = layout.level_size(level);
            let start = layout.block_offset(0, level);
            let end = start + (w * h * layout.faces()) as usize;
            (start..end)
                .map(|i| {
                    let mut texel = [1.0f32; 4];
                    for (c, v) in texel.iter_mut().take(channels).enumerate() {
                        *v = map[c][i];
                    }
                    texel
                })
                .collect()
        })
        .collect();
    let (width, height) = layout.level_size(0);
    Ok(ktx2::Texture {
        width,
        height,
        faces: layout.faces(),
        premultiplied: spec.layer == MapLayer::Local,
        levels,
        writer,
    })
}
