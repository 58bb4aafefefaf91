//! What the encoder consumes: parameterized textures over a 1D or 2D
//! parameter grid, each with a MIP chain and optionally six cube faces.
//!
//! One sample's texels are laid out exactly like the decoder's output
//! ([`LeafLayout`]), so the inference side can hand its buffers over as is.

use crate::error::{CodecError, Result};

/// Hard limits; the container parser enforces the same ones.
pub const MAX_DIM: u32 = 8192;
pub const MAX_SAMPLES_PER_DIM: u32 = 1 << 16;
pub const MAX_SAMPLES: u64 = 1 << 20;

/// Identifies one texture of a scene: which object and which shading layer
/// (e.g. 0 = distant EM, 1 = local EM).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TextureId {
    pub object: u32,
    pub layer: u32,
}

/// The parameter grid: 1D (`n1 == 1`, e.g. a viewpoint orbit) or 2D.
/// Sample `(i0, i1)` has linear index `i0 + n0 * i1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamGrid {
    pub n0: u32,
    pub n1: u32,
}

impl ParamGrid {
    pub fn one_d(n: u32) -> Self {
        Self { n0: n, n1: 1 }
    }
    pub fn two_d(n0: u32, n1: u32) -> Self {
        Self { n0, n1 }
    }
    pub fn dims(&self) -> usize {
        if self.n1 > 1 { 2 } else { 1 }
    }
    pub fn len(&self) -> usize {
        self.n0 as usize * self.n1 as usize
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// `(i0, i1)` of linear index `linear` (the inverse of [`index`](Self::index);
    /// an index past the grid gives coordinates `index` rejects).
    pub fn sample_at(&self, linear: u32) -> [u32; 2] {
        let n0 = self.n0.max(1);
        [linear % n0, linear / n0]
    }
    /// Linear index of `(i0, i1)`, or an error when out of range.
    pub fn index(&self, sample: [u32; 2]) -> Result<usize> {
        if sample[0] >= self.n0 {
            return Err(CodecError::IndexOutOfRange {
                what: "sample[0]",
                got: sample[0] as u64,
                limit: self.n0 as u64,
            });
        }
        if sample[1] >= self.n1 {
            return Err(CodecError::IndexOutOfRange {
                what: "sample[1]",
                got: sample[1] as u64,
                limit: self.n1 as u64,
            });
        }
        Ok(sample[0] as usize + self.n0 as usize * sample[1] as usize)
    }
}

/// The texel geometry of one parameter sample: faces × MIP chain.
///
/// Layout of one sample (input and decoder output alike): MIP-major, then
/// face, then rows top to bottom, then texels left to right, then channels;
/// tightly packed. MIP `m` has size `max(1, width >> m) × max(1, height >> m)`.
/// MIP-major order lets the engine copy each MIP level of all six faces with
/// one `VkBufferImageCopy` region (`layerCount = 6`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeafLayout {
    pub width: u32,
    pub height: u32,
    pub faces: u32,
    pub mips: u32,
    pub channels: u32,
}

impl LeafLayout {
    pub fn mip_size(&self, mip: u32) -> (usize, usize) {
        (
            (self.width >> mip).max(1) as usize,
            (self.height >> mip).max(1) as usize,
        )
    }
    /// Texels (not elements) of one face at `mip`.
    pub fn face_texels(&self, mip: u32) -> usize {
        let (w, h) = self.mip_size(mip);
        w * h
    }
    /// Texels of one whole sample (all faces, all MIPs).
    pub fn texels(&self) -> usize {
        (0..self.mips)
            .map(|m| self.face_texels(m) * self.faces as usize)
            .sum()
    }
    /// Offset in texels of `(face, mip)` within one sample.
    pub fn texel_offset(&self, face: u32, mip: u32) -> usize {
        let before: usize = (0..mip)
            .map(|m| self.face_texels(m) * self.faces as usize)
            .sum();
        before + face as usize * self.face_texels(mip)
    }
    /// Largest allowed MIP count for this size (a full chain down to 1×1).
    pub fn max_mips(width: u32, height: u32) -> u32 {
        32 - width.max(height).max(1).leading_zeros()
    }
}

/// One parameterized texture: an image stack over a parameter grid.
#[derive(Clone, Debug)]
pub struct ParamTexture {
    pub id: TextureId,
    pub grid: ParamGrid,
    pub layout: LeafLayout,
    /// Screen area (pixels, or any consistent unit) this texture covers; it
    /// weights its squared error in the rate allocation.
    pub screen_area: f32,
    /// All samples back to back, sample-major; each sample in [`LeafLayout`]
    /// order with `layout.channels` floats per texel (3 = RGB, 4 = RGBA with
    /// linear coverage alpha). Linear radiance; any range, not clipped.
    pub data: Vec<f32>,
}

impl ParamTexture {
    /// A zero-filled texture to be filled through [`ParamTexture::sample_mut`].
    pub fn zeroed(id: TextureId, grid: ParamGrid, layout: LeafLayout, screen_area: f32) -> Self {
        let n = grid.len() * layout.texels() * layout.channels as usize;
        Self {
            id,
            grid,
            layout,
            screen_area,
            data: vec![0.0; n],
        }
    }
    pub fn sample_len(&self) -> usize {
        self.layout.texels() * self.layout.channels as usize
    }
    pub fn sample(&self, s: usize) -> &[f32] {
        let n = self.sample_len();
        &self.data[s * n..(s + 1) * n]
    }
    pub fn sample_mut(&mut self, s: usize) -> &mut [f32] {
        let n = self.sample_len();
        &mut self.data[s * n..(s + 1) * n]
    }
    /// Uncompressed size as 32-bit floats: the reference for compression ratios.
    pub fn raw_bytes(&self) -> u64 {
        self.data.len() as u64 * 4
    }

    /// Checks the description and that every value is finite.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| CodecError::BadInput {
            object: self.id.object,
            layer: self.id.layer,
            what,
        };
        let l = &self.layout;
        if l.width == 0 || l.height == 0 || l.width > MAX_DIM || l.height > MAX_DIM {
            return Err(bad(format!(
                "size {}x{} outside 1..={MAX_DIM}",
                l.width, l.height
            )));
        }
        if l.faces != 1 && l.faces != 6 {
            return Err(bad(format!("faces = {}, expected 1 or 6", l.faces)));
        }
        if l.channels != 3 && l.channels != 4 {
            return Err(bad(format!("channels = {}, expected 3 or 4", l.channels)));
        }
        let max_mips = LeafLayout::max_mips(l.width, l.height);
        if l.mips == 0 || l.mips > max_mips {
            return Err(bad(format!("mips = {}, expected 1..={max_mips}", l.mips)));
        }
        let g = &self.grid;
        if g.n0 == 0 || g.n1 == 0 || g.n0 > MAX_SAMPLES_PER_DIM || g.n1 > MAX_SAMPLES_PER_DIM {
            return Err(bad(format!(
                "parameter grid {}x{} out of range",
                g.n0, g.n1
            )));
        }
        if g.len() as u64 > MAX_SAMPLES {
            return Err(bad(format!("{} samples exceed {MAX_SAMPLES}", g.len())));
        }
        if !(self.screen_area.is_finite() && self.screen_area >= 0.0) {
            return Err(bad(format!("screen_area = {}", self.screen_area)));
        }
        let expected = g.len() * self.sample_len();
        if self.data.len() != expected {
            return Err(bad(format!(
                "data holds {} floats, expected {expected}",
                self.data.len()
            )));
        }
        let n = self.sample_len();
        if let Some((i, v)) = self.data.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CodecError::NonFinite {
                object: self.id.object,
                layer: self.id.layer,
                sample: i / n,
                element: i % n,
                value: *v,
            });
        }
        Ok(())
    }
}

/// Everything one container holds: every texture of a scene.
#[derive(Clone, Debug, Default)]
pub struct EncodeInput {
    pub textures: Vec<ParamTexture>,
}

impl EncodeInput {
    pub fn raw_bytes(&self) -> u64 {
        self.textures.iter().map(|t| t.raw_bytes()).sum()
    }
    pub fn validate(&self) -> Result<()> {
        if self.textures.is_empty() {
            return Err(CodecError::BadRequest("no textures".into()));
        }
        let mut ids: Vec<TextureId> = self.textures.iter().map(|t| t.id).collect();
        ids.sort();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(CodecError::BadRequest(format!(
                "duplicate texture (object {}, layer {})",
                w[0].object, w[0].layer
            )));
        }
        self.textures.iter().try_for_each(|t| t.validate())
    }
}
