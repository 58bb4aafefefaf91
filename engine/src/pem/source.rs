//! Where playback gets a sample's maps: the compressed container (default;
//! decoded straight into the caller's staging memory) or the inferred EXR
//! files themselves. Both write the same layout: RGBA f16, MIP-major, then
//! face, then rows — what `level_regions` uploads.

use crate::backend::host_image::HostElement;
pub use crate::maps::MapLayer;
use crate::maps::{MapSet, map_path};
use anyhow::{Context, Result, bail};
use codec::LeafSink;
use half::f16;
use inference::infer::maps::read_map;
use inference::scene::Scene;
use inference::solve::layout::TextureLayout;
use std::path::{Path, PathBuf};

/// Which source playback reads maps from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SourceKind {
    /// The codec container (`engine encode`), decoded per sample.
    #[default]
    Container,
    /// The inferred EXR maps, read per sample (uncompressed).
    Exr,
}

pub struct MapSource {
    kind: Kind,
    /// What a read took, for the counters.
    pub last_read_ms: f64,
}

enum Kind {
    Container {
        path: PathBuf,
        container: Box<codec::Container>,
        cache: Box<codec::DecodeCache>,
        /// (object name, layer) → container texture (object index).
        index: Vec<(String, &'static str, u32)>,
    },
    Exr {
        dir: PathBuf,
    },
}

impl MapSource {
    /// Bytes of the container file (None when reading EXR maps).
    pub fn container_bytes(&self) -> Option<u64> {
        match &self.kind {
            Kind::Container { path, .. } => std::fs::metadata(path).ok().map(|m| m.len()),
            Kind::Exr { .. } => None,
        }
    }

    /// Seconds the container took to compile (its inputs' traces and maps
    /// and its encode), as its key record keeps them; None when reading
    /// EXR maps or when the record has none.
    pub fn compile_seconds(&self) -> Option<f64> {
        match &self.kind {
            Kind::Container { path, .. } => inference::key::recorded_seconds(path),
            Kind::Exr { .. } => None,
        }
    }

    /// Opens the container at `path`, checking it holds the maps this scene
    /// asks for, in the order `engine encode` writes them.
    pub fn container(scene: &Scene, path: &Path) -> Result<Self> {
        Self::container_of(scene, MapSet::Scene, path)
    }

    /// Opens the container of `set` at `path`, checking it holds that
    /// set's maps, in order.
    pub fn container_of(scene: &Scene, set: MapSet, path: &Path) -> Result<Self> {
        // Its errors name the file.
        let container = codec::Container::open(path).context("opening the map container")?;
        let specs = set.specs(scene);
        let textures = container.textures();
        if textures.len() != specs.len() {
            bail!(
                "{}: holds {} textures, scene {} asks for {} (re-run `engine encode --scene {}`)",
                path.display(),
                textures.len(),
                scene.name,
                specs.len(),
                scene.arg()
            );
        }
        let mut index = Vec::new();
        for (i, (spec, tex)) in specs.iter().zip(textures).enumerate() {
            let layout = spec.layout();
            let (w, h) = layout.level_size(0);
            let got = (
                tex.layout.width,
                tex.layout.height,
                tex.layout.faces,
                tex.layout.channels,
            );
            let want = (w, h, layout.faces(), spec.layer.channels() as u32);
            // A 1D container lists the samples in order; a 2D one must be
            // the orbit's azimuth lines × rings.
            let grid_ok = tex.grid.len() >= scene.orbit.sample_count() as usize
                && (tex.grid.n1 == 1 || tex.grid.n0 == scene.orbit.samples);
            if got != want || !grid_ok {
                bail!(
                    "{}: texture {i} ({}) is {}x{}x{} faces, {} channels, {}x{} samples; expected {}x{}x{}, {} channels, {} samples ({} per ring) (re-run `engine encode`)",
                    path.display(),
                    spec.name(),
                    got.0,
                    got.1,
                    got.2,
                    got.3,
                    tex.grid.n0,
                    tex.grid.n1,
                    want.0,
                    want.1,
                    want.2,
                    want.3,
                    scene.orbit.sample_count(),
                    scene.orbit.samples
                );
            }
            index.push((spec.object.clone(), spec.layer.file_part(), i as u32));
        }
        Ok(Self {
            kind: Kind::Container {
                path: path.to_owned(),
                container: Box::new(container),
                cache: Box::default(),
                index,
            },
            last_read_ms: 0.0,
        })
    }

    /// Reads the EXR maps under `dir` (`sample_XXXX/<object>.<layer>.exr`).
    pub fn exr(dir: &Path) -> Self {
        Self {
            kind: Kind::Exr {
                dir: dir.to_owned(),
            },
            last_read_ms: 0.0,
        }
    }

    /// A second, independent handle on the same maps (for a worker thread).
    pub fn reopen(&self) -> Result<Self> {
        let kind = match &self.kind {
            Kind::Container { path, index, .. } => Kind::Container {
                path: path.clone(),
                container: Box::new(
                    codec::Container::open(path).context("opening the map container")?,
                ),
                cache: Box::default(),
                index: index.clone(),
            },
            Kind::Exr { dir } => Kind::Exr { dir: dir.clone() },
        };
        Ok(Self {
            kind,
            last_read_ms: 0.0,
        })
    }

    /// Whether this source can give `layer` of `object` (containers hold
    /// only what `engine encode` put in them).
    pub fn has(&self, object: &str, layer: MapLayer) -> bool {
        match &self.kind {
            Kind::Container { index, .. } => index
                .iter()
                .any(|(o, l, _)| o == object && *l == layer.file_part()),
            Kind::Exr { dir } => map_path(dir, 0, object, layer).is_file(),
        }
    }

    /// Decodes a share of the coarse pyramid levels the next samples of
    /// `object`'s `layer` will need, along the way the reads have been
    /// moving (`codec::DecodeCache::warm_ahead`), so a new pyramid block
    /// makes no read 3–4× the others. The decode-ahead worker calls it
    /// after handing over a map, in its idle time. Only a head start:
    /// nothing for EXR maps, and a block failing here fails again, with
    /// its error, when a read needs it.
    pub fn warm_ahead(&mut self, object: &str, layer: MapLayer) {
        if let Kind::Container {
            container,
            cache,
            index,
            ..
        } = &mut self.kind
            && let Some(&(_, _, texture)) = index
                .iter()
                .find(|(o, l, _)| o == object && *l == layer.file_part())
        {
            let _ = cache.warm_ahead(container, texture, 0);
        }
    }

    /// Writes sample `sample` of `object`'s `layer` (a `resolution` map with
    /// its full MIP chain) into `out`: RGBA f16, alpha 1 for RGB maps.
    pub fn read(
        &mut self,
        object: &str,
        layer: MapLayer,
        resolution: u32,
        sample: u32,
        out: &mut [f16],
    ) -> Result<()> {
        let start = std::time::Instant::now();
        let layout = TextureLayout::full_chain(layer.shape(resolution));
        if out.len() != layout.len() * 4 {
            bail!(
                "staging slice of {} halves for {object}.{} (expected {})",
                out.len(),
                layer.file_part(),
                layout.len() * 4
            );
        }
        match &mut self.kind {
            Kind::Container {
                path,
                container,
                cache,
                index,
            } => {
                let (texture, at) = locate((path, container, index), object, layer, sample)?;
                cache
                    .decode_leaf_all(container, texture, 0, at, out)
                    .with_context(|| {
                        format!(
                            "{}: decoding {object}.{} of sample {sample}",
                            path.display(),
                            layer.file_part()
                        )
                    })?;
                cache.end_frame();
            }
            Kind::Exr { dir } => {
                let path = map_path(dir, sample, object, layer);
                let map = read_map(&path, &layout, layer.channels())
                    .with_context(|| format!("reading inferred map {}", path.display()))?;
                for (i, texel) in out.chunks_exact_mut(4).enumerate() {
                    for (c, v) in texel.iter_mut().enumerate() {
                        let x = map.get(c).map_or(1.0, |m| m[i]);
                        *v = f16::from_f32(x);
                        if v.is_infinite() {
                            bail!(
                                "{}: holds {x:e}, beyond what playback's f16 textures hold (±65504)",
                                path.display()
                            );
                        }
                    }
                }
            }
        }
        self.last_read_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// [`Self::read`] straight into a slot's texels: levels below `drop`
    /// (the finest, which the slot's arrays leave out) are not written.
    pub fn read_into_slot(
        &mut self,
        key: (&str, MapLayer, u32, u32),
        slot: &mut HostElement,
        drop: u32,
    ) -> Result<()> {
        let (object, layer, resolution, sample) = key;
        let start = std::time::Instant::now();
        let mut sink = SlotSink {
            slot,
            drop,
            written: 0,
        };
        if let Kind::Container {
            path,
            container,
            cache,
            index,
        } = &mut self.kind
        {
            let (texture, at) = locate((path, container, index), object, layer, sample)?;
            cache
                .decode_leaf_into(container, texture, 0, at, &mut sink)
                .with_context(|| {
                    format!(
                        "{}: decoding {object}.{} of sample {sample} into its slot",
                        path.display(),
                        layer.file_part()
                    )
                })?;
            cache.end_frame();
        } else {
            // EXR maps: read whole, then level by level into the slot.
            let layout = TextureLayout::full_chain(layer.shape(resolution));
            let mut leaf = vec![f16::ZERO; layout.len() * 4];
            self.read(object, layer, resolution, sample, &mut leaf)?;
            for level in drop..layout.levels() {
                for face in 0..layout.faces() {
                    let (w, h) = layout.level_size(level);
                    let n = (w * h) as usize * 4;
                    let at = layout.block_offset(face, level) * 4;
                    let Some(dst) = sink.level(face, level, n / 4) else {
                        continue;
                    };
                    let src = leaf.get(at..at + n).unwrap_or_default();
                    if dst.len() != src.len() {
                        bail!(
                            "{object}.{}: level {level} does not fit its slot",
                            layer.file_part()
                        );
                    }
                    dst.copy_from_slice(src);
                }
            }
        }
        // Maps with fewer levels or faces than the slot would leave the
        // last sample's texels in the rest.
        let (written, wanted) = (sink.written, sink.slot.subresources());
        if written != wanted {
            bail!(
                "{object}.{} of sample {sample} filled {written} of its slot's {wanted} levels × faces",
                layer.file_part()
            );
        }
        self.last_read_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }
}

/// The container texture holding `object`'s `layer`, and where `sample`
/// lies on its grid.
fn locate(
    (path, container, index): (&Path, &codec::Container, &[(String, &'static str, u32)]),
    object: &str,
    layer: MapLayer,
    sample: u32,
) -> Result<(u32, [u32; 2])> {
    let Some(&(_, _, texture)) = index
        .iter()
        .find(|(o, l, _)| o == object && *l == layer.file_part())
    else {
        bail!(
            "{}: holds no {object}.{} maps",
            path.display(),
            layer.file_part()
        );
    };
    let Some(grid) = container.textures().get(texture as usize).map(|t| t.grid) else {
        bail!("{}: holds no texture {texture}", path.display());
    };
    Ok((texture, grid.sample_at(sample)))
}

/// The decoder's levels into a lent slot, the `drop` finest skipped.
struct SlotSink<'a> {
    slot: &'a mut HostElement,
    drop: u32,
    /// Levels × faces handed out.
    written: usize,
}

impl LeafSink<f16> for SlotSink<'_> {
    fn level(&mut self, face: u32, mip: u32, texels: usize) -> Option<&mut [f16]> {
        let level = mip.checked_sub(self.drop)?;
        // A level that will not fit (or is misaligned) gives an empty
        // slice, which the decoder reports as the wrong size.
        let bytes = self.slot.level_mut(face, level, texels * 8);
        let halves = bytes.and_then(|b| bytemuck::try_cast_slice_mut(b).ok());
        self.written += usize::from(halves.is_some());
        Some(halves.unwrap_or_default())
    }
}
