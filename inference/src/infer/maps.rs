//! Inferred maps on disk: one multi-part EXR per map, one part per MIP
//! level named `mip<l>`, the faces of a cube side by side in Vulkan order
//! (+X, −X, +Y, −Y, +Z, −Z), f32 channels R, G, B (and A). Written to a
//! temporary name and renamed, so a file is either whole or absent.

use crate::files::{ExrHeader, check_exr_size};
use crate::solve::layout::TextureLayout;
use exr::prelude::{
    AnyChannel, AnyChannels, FlatSamples, Image, ImageAttributes, IntegerBounds, Layer,
    LayerAttributes, ReadChannels, ReadLayers, SmallVec, Text, Vec2, WritableImage, read,
};
use std::path::{Path, PathBuf};

const CHANNELS: [&str; 4] = ["R", "G", "B", "A"];

#[derive(Debug, thiserror::Error)]
pub enum MapError {
    #[error("{path}: {cause}")]
    Exr {
        path: PathBuf,
        cause: exr::error::Error,
    },
    #[error("{path}: {cause}")]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{path}: {what} (expected {expected})")]
    Shape {
        path: PathBuf,
        what: String,
        expected: String,
    },
}

/// Writes `map` (one Vec per channel, `layout` order) to `path`.
pub fn write_map(path: &Path, layout: &TextureLayout, map: &[Vec<f32>]) -> Result<(), MapError> {
    let faces = layout.faces();
    let layers: Vec<Layer<AnyChannels<FlatSamples>>> = (0..layout.levels())
        .map(|level| {
            let (w, h) = layout.level_size(level);
            let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = map
                .iter()
                .zip(CHANNELS)
                .map(|(channel, name)| {
                    let mut samples = Vec::with_capacity((w * h * faces) as usize);
                    for y in 0..h {
                        for face in 0..faces {
                            for x in 0..w {
                                samples.push(channel[layout.index(face, level, x, y)]);
                            }
                        }
                    }
                    AnyChannel::new(name, FlatSamples::F32(samples))
                })
                .collect();
            Layer::new(
                Vec2((w * faces) as usize, h as usize),
                LayerAttributes::named(format!("mip{level}").as_str()),
                crate::files::EXR_ENCODING,
                AnyChannels::sort(channels),
            )
        })
        .collect();
    let (w0, h0) = layout.level_size(0);
    let attributes = ImageAttributes::new(IntegerBounds::from_dimensions(Vec2(
        (w0 * faces) as usize,
        h0 as usize,
    )));
    crate::files::write_with(path, |tmp| {
        Image::from_layers(attributes, layers)
            .write()
            .to_file(tmp)
            .map_err(|cause| MapError::Exr {
                path: path.to_owned(),
                cause,
            })
    })
    .map_err(|e| match e {
        crate::files::AtomicError::Write(e) => e,
        crate::files::AtomicError::Rename { path, source } => MapError::Io {
            path,
            cause: source,
        },
    })
}

/// Reads a map written by [`write_map`] for `layout` with `channels`
/// channels; any mismatch is an error naming the file and what differs.
pub fn read_map(
    path: &Path,
    layout: &TextureLayout,
    channels: usize,
) -> Result<Vec<Vec<f32>>, MapError> {
    let bytes = std::fs::read(path).map_err(|cause| MapError::Io {
        path: path.to_owned(),
        cause,
    })?;
    parse_map(&bytes, path, layout, channels)
}

/// [`read_map`] on the file's bytes, already read (and checked); `path`
/// names the file in errors.
pub fn parse_map(
    bytes: &[u8],
    path: &Path,
    layout: &TextureLayout,
    channels: usize,
) -> Result<Vec<Vec<f32>>, MapError> {
    if !(1..=CHANNELS.len()).contains(&channels) {
        return Err(MapError::Shape {
            path: path.to_owned(),
            what: format!("{channels} channels asked for"),
            expected: "1 to 4 channels".into(),
        });
    }
    check_exr_size(bytes).map_err(|e| match e {
        ExrHeader::Unreadable(cause) => MapError::Exr {
            path: path.to_owned(),
            cause,
        },
        ExrHeader::TooLarge(declared) => MapError::Shape {
            path: path.to_owned(),
            what: format!("its header declares {declared}"),
            expected: format!("a map of {} texels", layout.len()),
        },
    })?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|cause| MapError::Exr {
            path: path.to_owned(),
            cause,
        })?;
    let reading = Reading {
        path,
        layout,
        channels,
    };
    let mut map = vec![vec![0.0f32; layout.len()]; channels];
    for level in 0..layout.levels() {
        let part = reading.level_part(&image.layer_data, level)?;
        for (c, out) in map.iter_mut().enumerate() {
            reading.copy_channel(part, level, c, out)?;
        }
    }
    Ok(map)
}

/// One EXR part (a MIP level) with its channels as read.
type Part = Layer<AnyChannels<FlatSamples>>;

/// A map being read: the file (named in errors), and the layout and
/// channel count it must have.
struct Reading<'a> {
    path: &'a Path,
    layout: &'a TextureLayout,
    channels: usize,
}

impl Reading<'_> {
    fn shape(&self, what: String, expected: String) -> MapError {
        MapError::Shape {
            path: self.path.to_owned(),
            what,
            expected,
        }
    }

    /// The part named `mip<level>`, checked to hold the level's faces side
    /// by side.
    fn level_part<'i>(&self, parts: &'i [Part], level: u32) -> Result<&'i Part, MapError> {
        let name = format!("mip{level}");
        let part = parts
            .iter()
            .find(|l| {
                l.attributes
                    .layer_name
                    .as_ref()
                    .map(Text::to_string)
                    .as_deref()
                    == Some(name.as_str())
            })
            .ok_or_else(|| {
                self.shape(
                    format!("no part {name}"),
                    format!("{} MIP levels", self.layout.levels()),
                )
            })?;
        let (w, h) = self.layout.level_size(level);
        let faces = self.layout.faces();
        if part.size != Vec2((w * faces) as usize, h as usize) {
            return Err(self.shape(
                format!("part {name} is {}x{}", part.size.0, part.size.1),
                format!("{}x{h}", w * faces),
            ));
        }
        Ok(part)
    }

    /// Copies channel `c` (R, G, B, A) of MIP `level`'s part into `out`, in
    /// layout order; every value must be finite.
    fn copy_channel(
        &self,
        part: &Part,
        level: u32,
        c: usize,
        out: &mut [f32],
    ) -> Result<(), MapError> {
        let name = format!("mip{level}");
        let channel = part
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name.to_string() == CHANNELS[c])
            .ok_or_else(|| {
                self.shape(
                    format!("part {name} has no channel {}", CHANNELS[c]),
                    format!("{} channels", self.channels),
                )
            })?;
        let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
        let (w, h) = self.layout.level_size(level);
        let faces = self.layout.faces();
        if values.len() != (w * faces * h) as usize {
            return Err(self.shape(
                format!(
                    "part {name} channel {} holds {} samples",
                    CHANNELS[c],
                    values.len()
                ),
                format!("{} (no subsampling)", w * faces * h),
            ));
        }
        for y in 0..h {
            for face in 0..faces {
                for x in 0..w {
                    let v = values[((y * faces + face) * w + x) as usize];
                    if !v.is_finite() {
                        return Err(
                            self.shape(format!("part {name} holds {v}"), "finite values".into())
                        );
                    }
                    out[self.layout.index(face, level, x, y)] = v;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::layout::TextureShape;

    #[test]
    fn cube_map_round_trips_and_mismatches_are_named() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("m.exr");
        let layout = TextureLayout::full_chain(TextureShape::Cube { size: 8 });
        let map: Vec<Vec<f32>> = (0..4)
            .map(|c| {
                (0..layout.len())
                    .map(|i| (i * 4 + c) as f32 * 1e3)
                    .collect()
            })
            .collect();
        write_map(&path, &layout, &map).expect("write");
        assert_eq!(read_map(&path, &layout, 4).expect("read"), map);
        let other = TextureLayout::full_chain(TextureShape::Cube { size: 16 });
        let err = read_map(&path, &other, 4)
            .expect_err("size mismatch")
            .to_string();
        assert!(err.contains("m.exr") && err.contains("mip0"), "{err}");
        assert!(!dir.path().join("m.exr.tmp").exists());
    }

    #[test]
    fn the_same_map_is_written_as_the_same_bytes() {
        let dir = tempfile::tempdir().expect("tempdir");
        let layout = TextureLayout::full_chain(TextureShape::Cube { size: 256 });
        let map: Vec<Vec<f32>> = (0..4)
            .map(|c| {
                (0..layout.len())
                    .map(|i| ((i * 7 + c) % 97) as f32)
                    .collect()
            })
            .collect();
        let bytes = |name: &str| {
            let path = dir.path().join(name);
            write_map(&path, &layout, &map).expect("write");
            std::fs::read(&path).expect("read back")
        };
        // Many blocks compressed in parallel, each written in row order.
        assert!(bytes("a.exr") == bytes("b.exr"), "the bytes differ");
        let meta =
            exr::meta::MetaData::read_from_file(dir.path().join("a.exr"), false).expect("header");
        assert!(
            meta.headers
                .iter()
                .all(|h| h.line_order == exr::prelude::LineOrder::Increasing)
        );
    }
}
