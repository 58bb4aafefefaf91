//! Files: one multi-part EXR per image (one part per layer, f32, never clipped) and a
//! tone-mapped PNG of `beauty`. Both are written to temporary names and renamed into place
//! only when both succeeded, so a failed run leaves no partial files.

use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, FlatSamples, Image, ImageAttributes, IntegerBounds, Layer,
    LayerAttributes, ReadChannels, ReadLayers, SmallVec, Text, Vec2, WritableImage, read,
};

use super::TraceImage;
use super::error::TraceError;
use crate::files::ExrHeader;

/// Writes `<stem>.exr` and `<stem>.png`; returns their paths.
pub fn write_image(stem: &Path, image: &TraceImage) -> Result<(PathBuf, PathBuf), TraceError> {
    let exr_path = with_suffix(stem, ".exr");
    let png_path = with_suffix(stem, ".png");
    let exr_tmp = crate::files::temp_path(&exr_path);
    let png_tmp = crate::files::temp_path(&png_path);
    let result = write_exr(&exr_tmp, image)
        .and_then(|()| write_png(&png_tmp, image))
        .and_then(|()| rename(&exr_tmp, &exr_path))
        .and_then(|()| rename(&png_tmp, &png_path));
    if result.is_err() {
        for p in [&exr_tmp, &png_tmp] {
            let _ = std::fs::remove_file(p);
        }
    }
    result.map(|()| (exr_path, png_path))
}

/// `stem` + `suffix`, keeping dots inside the stem (`view_-12.5` + `.exr`), unlike
/// `Path::with_extension`.
pub fn with_suffix(stem: &Path, suffix: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

fn rename(from: &Path, to: &Path) -> Result<(), TraceError> {
    std::fs::rename(from, to).map_err(|e| TraceError::io(to, e))
}

/// All layers of `image` as parts of one EXR at `path` (exact layer names, f32 samples).
pub fn write_exr(path: &Path, image: &TraceImage) -> Result<(), TraceError> {
    let size = Vec2(image.width as usize, image.height as usize);
    let layers: Vec<Layer<AnyChannels<FlatSamples>>> = image
        .layers
        .iter()
        .map(|layer| {
            let n = layer.channels.len();
            let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = layer
                .channels
                .iter()
                .enumerate()
                .map(|(c, name)| {
                    let samples = layer.pixels.iter().skip(c).step_by(n).copied().collect();
                    AnyChannel::new(*name, FlatSamples::F32(samples))
                })
                .collect();
            Layer::new(
                size,
                LayerAttributes::named(layer.name.as_str()),
                crate::files::EXR_ENCODING,
                AnyChannels::sort(channels),
            )
        })
        .collect();
    let attributes = ImageAttributes::new(IntegerBounds::from_dimensions(size));
    Image::from_layers(attributes, layers)
        .write()
        .to_file(path)
        .map_err(|cause| TraceError::Exr {
            path: path.to_owned(),
            cause,
        })
}

/// A layer read back: its name and `(channel name, samples)` pairs.
pub type ExrLayer = (String, Vec<(String, Vec<f32>)>);

/// Layer names and channel names of an EXR written by [`write_exr`], with the samples.
pub fn read_exr(path: &Path) -> Result<Vec<ExrLayer>, TraceError> {
    let bytes = std::fs::read(path).map_err(|e| TraceError::io(path, e))?;
    parse_exr(&bytes, path)
}

/// [`read_exr`] on the file's bytes, already read (and checked); `path`
/// names the file in errors.
pub fn parse_exr(bytes: &[u8], path: &Path) -> Result<Vec<ExrLayer>, TraceError> {
    crate::files::check_exr_size(bytes).map_err(|e| match e {
        ExrHeader::Unreadable(cause) => TraceError::Exr {
            path: path.to_owned(),
            cause,
        },
        ExrHeader::TooLarge(declared) => TraceError::ExrSize {
            path: path.to_owned(),
            declared,
        },
    })?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|cause| TraceError::Exr {
            path: path.to_owned(),
            cause,
        })?;
    Ok(image
        .layer_data
        .iter()
        .map(|layer| {
            let name = layer
                .attributes
                .layer_name
                .as_ref()
                .map_or_else(String::new, Text::to_string);
            let channels = layer
                .channel_data
                .list
                .iter()
                .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
                .collect();
            (name, channels)
        })
        .collect())
}

/// Narkowicz's ACES fit, then the sRGB curve: keeps highlights from clipping hard.
pub fn tone_map(x: f32) -> u8 {
    let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
    let t = ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
    let s = if t <= 0.003_130_8 {
        12.92 * t
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Tone-mapped 8-bit PNG of the `beauty` layer.
pub fn write_png(path: &Path, image: &TraceImage) -> Result<(), TraceError> {
    let bytes: Vec<u8> = image
        .layer("beauty")
        .map(|l| l.pixels.iter().map(|&v| tone_map(v)).collect())
        .unwrap_or_default();
    image::save_buffer_with_format(
        path,
        &bytes,
        image.width,
        image.height,
        image::ColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|cause| TraceError::Png {
        path: path.to_owned(),
        cause,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::layers::Layer as TraceLayer;

    #[test]
    fn an_exr_declaring_a_huge_frame_is_refused_before_it_is_read() {
        let image = TraceImage {
            width: 4,
            height: 3,
            layers: vec![TraceLayer {
                name: "beauty".into(),
                channels: vec!["R", "G", "B"],
                pixels: vec![0.5; 4 * 3 * 3],
            }],
            rays: 0,
            elapsed: std::time::Duration::ZERO,
        };
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("x.exr");
        write_exr(&path, &image).expect("write");
        let mut bytes = std::fs::read(&path).expect("read");
        assert_eq!(parse_exr(&bytes, &path).expect("reads")[0].1.len(), 3);
        // The data window: "dataWindow\0box2i\0", its size (16), then
        // xMin, yMin, xMax, yMax as little-endian i32.
        let tag = b"dataWindow\0box2i\0";
        let at = bytes
            .windows(tag.len())
            .position(|w| w == tag)
            .expect("tag");
        let max = at + tag.len() + 4 + 8;
        for k in [max, max + 4] {
            bytes[k..k + 4].copy_from_slice(&199_999i32.to_le_bytes());
        }
        let e = parse_exr(&bytes, &path)
            .expect_err("40 billion pixels")
            .to_string();
        assert!(e.contains("x.exr") && e.contains("200000x200000"), "{e}");
    }

    #[test]
    fn tone_map_is_monotone_and_safe() {
        assert_eq!(tone_map(0.0), 0);
        assert_eq!(tone_map(f32::NAN), 0);
        assert_eq!(tone_map(f32::INFINITY), 0);
        assert_eq!(tone_map(1e6), 255);
        let mut prev = 0;
        for i in 0..100 {
            let v = tone_map(i as f32 * 0.05);
            assert!(v >= prev);
            prev = v;
        }
    }
}
