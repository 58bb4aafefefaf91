//! A KTX 2.0 writer for uncompressed RGBA float textures: 2D maps and
//! cube maps with their MIP levels, as `VK_FORMAT_R32G32B32A32_SFLOAT`
//! (float32, so every texel survives the round trip bit for bit).
//!
//! File layout (KTX 2.0 specification, §3): the identifier; the header
//! (format, sizes, counts, then the byte offsets and lengths of the data
//! format descriptor, key/value data and supercompression global data);
//! the level index, one entry per MIP level from the base level down; the
//! data format descriptor (one basic block, Khronos Data Format
//! specification §5); the key/value data (`KTXwriter`); then the levels'
//! texels from the *smallest* level to the base, each level aligned to
//! lcm(texel block size, 4) = 16 bytes. Within a level: faces in Vulkan
//! order (+X, −X, +Y, −Y, +Z, −Z), rows, texels, channels R, G, B, A —
//! exactly what is copied into a Vulkan image.

use anyhow::{Result, bail};

/// `VK_FORMAT_R32G32B32A32_SFLOAT`.
pub const VK_FORMAT_R32G32B32A32_SFLOAT: u32 = 109;
/// «KTX 20»\r\n\x1A\n
pub const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];
/// Bytes of one texel (4 × f32), the format's texel block size.
const TEXEL_BYTES: usize = 16;
/// Level data alignment: lcm(texel block size, 4).
const LEVEL_ALIGN: usize = 16;
/// Identifier and header.
const HEADER_BYTES: usize = 80;
/// One level index entry: byteOffset, byteLength, uncompressedByteLength.
const LEVEL_INDEX_BYTES: usize = 24;

/// One texture to write: its base size, 1 face (2D) or 6 (a cube map),
/// and every MIP level's texels from the base level down.
pub struct Texture<'a> {
    pub width: u32,
    pub height: u32,
    /// 1 (a 2D texture) or 6 (a cube map).
    pub faces: u32,
    /// Whether R, G and B are premultiplied by A (flagged in the format
    /// descriptor).
    pub premultiplied: bool,
    /// `levels[l]`: level `l`'s texels, faces in Vulkan order, rows top to
    /// bottom; level sizes halve down to 1 (`max(1, size >> l)`).
    pub levels: Vec<Vec<[f32; 4]>>,
    /// The `KTXwriter` value, e.g. `pem-engine 0.1.0`.
    pub writer: &'a str,
}

impl Texture<'_> {
    fn level_size(&self, level: usize) -> (usize, usize) {
        (
            (self.width as usize >> level).max(1),
            (self.height as usize >> level).max(1),
        )
    }

    /// The texture's shape is one KTX 2.0 can hold and the levels hold
    /// exactly the texels their sizes ask for.
    fn check(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            bail!(
                "{}x{} texture: expected both sizes above 0",
                self.width,
                self.height
            );
        }
        match self.faces {
            1 => {}
            6 if self.width == self.height => {}
            6 => bail!(
                "{}x{} cube map: expected square faces",
                self.width,
                self.height
            ),
            n => bail!("{n} faces: expected 1 (2D) or 6 (a cube map)"),
        }
        let full = 32 - self.width.max(self.height).leading_zeros() as usize;
        if self.levels.is_empty() || self.levels.len() > full {
            bail!(
                "{} MIP levels for a {}x{} texture: expected 1 to {full}",
                self.levels.len(),
                self.width,
                self.height
            );
        }
        for (l, texels) in self.levels.iter().enumerate() {
            let (w, h) = self.level_size(l);
            let expected = w * h * self.faces as usize;
            if texels.len() != expected {
                bail!(
                    "MIP level {l} holds {} texels: expected {expected} ({w}x{h} × {} faces)",
                    texels.len(),
                    self.faces
                );
            }
        }
        Ok(())
    }
}

/// The file's bytes for `texture`.
pub fn encode(texture: &Texture) -> Result<Vec<u8>> {
    texture.check()?;
    let levels = texture.levels.len();
    let dfd = data_format_descriptor(texture.premultiplied);
    let kvd = key_value_data(&[("KTXwriter", texture.writer)]);
    let dfd_offset = HEADER_BYTES + LEVEL_INDEX_BYTES * levels;
    let kvd_offset = dfd_offset + dfd.len();
    let mut data_start = kvd_offset + kvd.len();

    // Levels from the smallest to the base, each after its mipPadding.
    let mut level_data = Vec::new();
    let mut index = vec![(0u64, 0u64); levels];
    for l in (0..levels).rev() {
        let pad = data_start.next_multiple_of(LEVEL_ALIGN) - data_start;
        level_data.resize(level_data.len() + pad, 0u8);
        data_start += pad;
        let bytes = texture.levels[l].len() * TEXEL_BYTES;
        index[l] = (data_start as u64, bytes as u64);
        for texel in &texture.levels[l] {
            for c in texel {
                level_data.extend_from_slice(&c.to_le_bytes());
            }
        }
        data_start += bytes;
    }

    let mut out = Vec::with_capacity(data_start);
    out.extend_from_slice(&IDENTIFIER);
    for word in [
        VK_FORMAT_R32G32B32A32_SFLOAT,
        4, // typeSize: bytes of one component
        texture.width,
        texture.height,
        0, // pixelDepth: not a 3D texture
        0, // layerCount: not an array
        texture.faces,
        levels as u32,
        0, // supercompressionScheme: none
        dfd_offset as u32,
        dfd.len() as u32,
        kvd_offset as u32,
        kvd.len() as u32,
    ] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteOffset: no global data
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteLength
    debug_assert_eq!(out.len(), HEADER_BYTES);
    for (offset, length) in index {
        for v in [offset, length, length] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    out.extend_from_slice(&level_data);
    Ok(out)
}

/// The data format descriptor of R32G32B32A32_SFLOAT: its total size,
/// then one basic descriptor block (RGBSDA colour model, BT.709
/// primaries, linear transfer) with four 32-bit signed float samples.
fn data_format_descriptor(premultiplied: bool) -> Vec<u8> {
    const KHR_DF_MODEL_RGBSDA: u32 = 1;
    const KHR_DF_PRIMARIES_BT709: u32 = 1;
    const KHR_DF_TRANSFER_LINEAR: u32 = 1;
    const KHR_DF_FLAG_ALPHA_PREMULTIPLIED: u32 = 1;
    const KHR_DF_SAMPLE_DATATYPE_FLOAT: u32 = 0x80;
    const KHR_DF_SAMPLE_DATATYPE_SIGNED: u32 = 0x40;
    // Channel ids of the RGBSDA model: R, G, B and alpha.
    const CHANNELS: [u32; 4] = [0, 1, 2, 15];
    let block_size = 24 + 16 * CHANNELS.len() as u32;
    let flags = if premultiplied {
        KHR_DF_FLAG_ALPHA_PREMULTIPLIED
    } else {
        0
    };
    let mut words = vec![
        4 + block_size,         // dfdTotalSize
        0,                      // vendorId = Khronos, descriptorType = basic
        2 | (block_size << 16), // versionNumber 2 (KDF 1.3), descriptorBlockSize
        KHR_DF_MODEL_RGBSDA
            | (KHR_DF_PRIMARIES_BT709 << 8)
            | (KHR_DF_TRANSFER_LINEAR << 16)
            | (flags << 24),
        0,                  // texelBlockDimension0..3: 1×1×1×1 (stored minus one)
        TEXEL_BYTES as u32, // bytesPlane0
        0,                  // bytesPlane4..7
    ];
    for (i, id) in CHANNELS.into_iter().enumerate() {
        let channel_type = id | KHR_DF_SAMPLE_DATATYPE_FLOAT | KHR_DF_SAMPLE_DATATYPE_SIGNED;
        // bitOffset, bitLength − 1, channelType; then the sample position,
        // and the float range's lower and upper bounds (−1.0, 1.0).
        words.push((32 * i as u32) | (31 << 16) | (channel_type << 24));
        words.push(0);
        words.push((-1.0f32).to_bits());
        words.push(1.0f32.to_bits());
    }
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Key/value pairs, sorted by key: each its byte length, the key and the
/// value NUL-terminated, padded to 4 bytes.
fn key_value_data(pairs: &[(&str, &str)]) -> Vec<u8> {
    let mut sorted = pairs.to_vec();
    sorted.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let mut out = Vec::new();
    for (key, value) in sorted {
        let length = key.len() + 1 + value.len() + 1;
        out.extend_from_slice(&(length as u32).to_le_bytes());
        out.extend_from_slice(key.as_bytes());
        out.push(0);
        out.extend_from_slice(value.as_bytes());
        out.push(0);
        out.resize(out.len().next_multiple_of(4), 0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(width: u32, height: u32, faces: u32, levels: usize) -> Texture<'static> {
        let mut n = 0.0f32;
        let levels = (0..levels)
            .map(|l| {
                let count = ((width as usize >> l).max(1))
                    * ((height as usize >> l).max(1))
                    * faces as usize;
                (0..count)
                    .map(|_| {
                        n += 1.0;
                        [n, -n, n * 1e-7, f32::from_bits(n as u32)]
                    })
                    .collect()
            })
            .collect();
        Texture {
            width,
            height,
            faces,
            premultiplied: false,
            levels,
            writer: "test",
        }
    }

    #[test]
    fn levels_are_stored_smallest_first_and_aligned() -> Result<()> {
        let t = ramp(8, 8, 6, 4);
        let bytes = encode(&t)?;
        assert_eq!(bytes[..12], IDENTIFIER);
        let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
        let offsets: Vec<u64> = (0..4).map(|l| u64_at(80 + 24 * l)).collect();
        assert!(offsets.windows(2).all(|w| w[0] > w[1]), "{offsets:?}");
        assert!(offsets.iter().all(|o| o % 16 == 0), "{offsets:?}");
        let last = offsets[0] + u64_at(88);
        assert_eq!(last as usize, bytes.len(), "the base level ends the file");
        Ok(())
    }

    /// An independent reader (the `ktx2` crate) finds the header, the
    /// format descriptor its own generator makes for this format, the
    /// writer's name and every texel's bits, NaN payloads included.
    #[test]
    fn the_ktx2_crate_reads_back_every_bit() -> Result<()> {
        for (faces, premultiplied) in [(6, false), (1, true)] {
            let mut t = ramp(16, 16, faces, 5);
            t.premultiplied = premultiplied;
            t.levels[2][3] = [f32::NAN, f32::from_bits(0x7fc0_1234), -0.0, f32::INFINITY];
            let bytes = encode(&t)?;
            let reader = ::ktx2::Reader::new(&bytes[..])?;
            let h = reader.header();
            assert_eq!(h.format, Some(::ktx2::Format::R32G32B32A32_SFLOAT));
            assert_eq!(
                (h.type_size, h.pixel_width, h.pixel_height, h.pixel_depth),
                (4, 16, 16, 0)
            );
            assert_eq!((h.layer_count, h.face_count, h.level_count), (0, faces, 5));
            assert_eq!(h.supercompression_scheme, None);
            let (expected, _) = ::ktx2::dfd::Basic::from_format_with(
                ::ktx2::Format::R32G32B32A32_SFLOAT,
                premultiplied,
                None,
                None,
                None,
            )?;
            assert_eq!(reader.dfd_blocks(), [::ktx2::dfd::Block::Basic(expected)]);
            assert_eq!(reader.writer(), Some("test\0"));
            for (level, texels) in reader.levels().zip(&t.levels) {
                let want: Vec<u8> = texels
                    .iter()
                    .flatten()
                    .flat_map(|c| c.to_le_bytes())
                    .collect();
                assert_eq!(level.data, &want[..]);
                assert_eq!(level.uncompressed_byte_length, want.len() as u64);
            }
        }
        Ok(())
    }

    #[test]
    fn bad_shapes_are_refused_by_name() {
        let mut t = ramp(8, 4, 6, 1);
        assert!(encode(&t).is_err_and(|e| e.to_string().contains("square")));
        t = ramp(8, 8, 3, 1);
        assert!(encode(&t).is_err_and(|e| e.to_string().contains("3 faces")));
        t = ramp(8, 8, 1, 2);
        t.levels[1].pop();
        assert!(encode(&t).is_err_and(|e| e.to_string().contains("MIP level 1")));
        t = ramp(4, 4, 1, 3);
        t.levels.push(vec![[0.0; 4]]);
        assert!(encode(&t).is_err_and(|e| e.to_string().contains("4 MIP levels")));
    }
}
