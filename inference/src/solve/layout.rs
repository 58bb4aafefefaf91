//! Where each texel of a MIP pyramid lives in the unknown vector `x`.
//!
//! Order: level-major, then face, then row-major within the face, so the
//! finest level of all faces comes first (the block the GPU sees most).

use super::SolveError;

/// Shape of the finest MIP level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureShape {
    Tex2D {
        width: u32,
        height: u32,
    },
    /// Six square faces in Vulkan face order (+X, −X, +Y, −Y, +Z, −Z).
    Cube {
        size: u32,
    },
}

impl TextureShape {
    fn base(&self) -> (u32, u32) {
        match *self {
            TextureShape::Tex2D { width, height } => (width, height),
            TextureShape::Cube { size } => (size, size),
        }
    }

    /// Number of levels of the full chain down to 1×1, like Vulkan.
    fn full_levels(&self) -> u32 {
        let (w, h) = self.base();
        32 - w.max(h).max(1).leading_zeros()
    }
}

/// Offsets of every (level, face) block of one channel of a MIP pyramid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureLayout {
    shape: TextureShape,
    levels: u32,
    /// `level_offset[l]` = index of texel (face 0, level l, 0, 0); one extra
    /// entry holds the total length.
    level_offset: Vec<usize>,
}

impl TextureLayout {
    /// `levels` in `1..=full chain`; level sizes halve with `max(1)`.
    pub fn new(shape: TextureShape, levels: u32) -> Result<Self, SolveError> {
        let (w, h) = shape.base();
        if w == 0 || h == 0 {
            return Err(SolveError::InvalidLayout {
                reason: format!("{shape:?} has a zero dimension"),
            });
        }
        let full = shape.full_levels();
        if levels == 0 || levels > full {
            return Err(SolveError::InvalidLayout {
                reason: format!("{levels} levels requested for {shape:?}, expected 1..={full}"),
            });
        }
        let faces: usize = match shape {
            TextureShape::Tex2D { .. } => 1,
            TextureShape::Cube { .. } => 6,
        };
        let mut level_offset = Vec::with_capacity(levels as usize + 1);
        let mut total = 0usize;
        for l in 0..levels {
            level_offset.push(total);
            let (lw, lh) = (((w >> l).max(1)) as usize, ((h >> l).max(1)) as usize);
            total = faces
                .checked_mul(lw)
                .and_then(|v| v.checked_mul(lh))
                .and_then(|v| v.checked_add(total))
                .filter(|&t| t <= u32::MAX as usize + 1)
                .ok_or_else(|| SolveError::InvalidLayout {
                    reason: format!(
                        "{shape:?} has more texels than u32 column indices can address"
                    ),
                })?;
        }
        level_offset.push(total);
        Ok(Self {
            shape,
            levels,
            level_offset,
        })
    }

    /// All levels down to 1×1. Shapes [`new`](Self::new) rejects (a zero
    /// dimension, more than 2³² texels) get an empty layout (`len() == 0`)
    /// rather than a panic.
    pub fn full_chain(shape: TextureShape) -> Self {
        let levels = shape.full_levels();
        Self::new(shape, levels).unwrap_or(Self {
            shape,
            levels: 0,
            level_offset: vec![0],
        })
    }

    pub fn shape(&self) -> TextureShape {
        self.shape
    }

    pub fn levels(&self) -> u32 {
        self.levels
    }

    pub fn faces(&self) -> u32 {
        match self.shape {
            TextureShape::Tex2D { .. } => 1,
            TextureShape::Cube { .. } => 6,
        }
    }

    /// (width, height) of `level`.
    pub fn level_size(&self, level: u32) -> (u32, u32) {
        let (w, h) = self.shape.base();
        ((w >> level).max(1), (h >> level).max(1))
    }

    /// Total texels of one channel (all faces, all levels).
    pub fn len(&self) -> usize {
        self.level_offset[self.levels as usize]
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of the first texel of (`face`, `level`).
    pub fn block_offset(&self, face: u32, level: u32) -> usize {
        let (w, h) = self.level_size(level);
        self.level_offset[level as usize] + face as usize * w as usize * h as usize
    }

    /// Panics if any coordinate is out of range (a caller bug, not input).
    pub fn index(&self, face: u32, level: u32, x: u32, y: u32) -> usize {
        let (w, h) = self.level_size(level);
        assert!(
            face < self.faces() && level < self.levels && x < w && y < h,
            "texel (face {face}, level {level}, {x}, {y}) outside {:?} with {} levels",
            self.shape,
            self.levels
        );
        self.block_offset(face, level) + y as usize * w as usize + x as usize
    }

    /// Inverse of [`index`](Self::index); panics if `index >= len()`.
    pub fn coords(&self, index: usize) -> (u32, u32, u32, u32) {
        assert!(index < self.len(), "texel index {index} >= {}", self.len());
        // Few levels: a linear scan beats a binary search here.
        let level = (0..self.levels)
            .rev()
            .find(|&l| self.level_offset[l as usize] <= index)
            .unwrap_or(0);
        let (w, h) = self.level_size(level);
        let within = index - self.level_offset[level as usize];
        let face_len = w as usize * h as usize;
        let face = within / face_len;
        let r = within % face_len;
        (
            face as u32,
            level,
            (r % w as usize) as u32,
            (r / w as usize) as u32,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_256_full_chain_len_and_roundtrip() {
        let l = TextureLayout::full_chain(TextureShape::Cube { size: 256 });
        assert_eq!(l.levels(), 9);
        let per_face: usize = (0..9).map(|k| (256usize >> k).pow(2)).sum();
        assert_eq!(l.len(), 6 * per_face);
        for i in [0, 1, 65535, 65536, 6 * 65536, l.len() - 1] {
            let (f, lv, x, y) = l.coords(i);
            assert_eq!(l.index(f, lv, x, y), i);
        }
        assert_eq!(l.index(1, 0, 0, 0), 65536); // face after level-0 face 0
        assert_eq!(l.index(0, 1, 0, 0), 6 * 65536); // level 1 after all faces
    }

    #[test]
    fn non_square_sizes_halve_with_floor_one() {
        let l = TextureLayout::full_chain(TextureShape::Tex2D {
            width: 8,
            height: 2,
        });
        assert_eq!(l.levels(), 4);
        let sizes: Vec<_> = (0..4).map(|k| l.level_size(k)).collect();
        assert_eq!(sizes, vec![(8, 2), (4, 1), (2, 1), (1, 1)]);
        assert_eq!(l.len(), 16 + 4 + 2 + 1);
        for i in 0..l.len() {
            let (f, lv, x, y) = l.coords(i);
            assert_eq!(l.index(f, lv, x, y), i);
        }
    }

    #[test]
    fn rejects_bad_levels_and_zero_sizes() {
        let s = TextureShape::Tex2D {
            width: 4,
            height: 4,
        };
        assert!(TextureLayout::new(s, 0).is_err());
        assert!(TextureLayout::new(s, 4).is_err());
        assert!(TextureLayout::new(s, 3).is_ok());
        assert!(TextureLayout::new(TextureShape::Cube { size: 0 }, 1).is_err());
        assert!(TextureLayout::full_chain(TextureShape::Cube { size: 0 }).is_empty());
        let huge = TextureShape::Cube { size: 1 << 30 };
        assert!(matches!(
            TextureLayout::new(huge, 1),
            Err(SolveError::InvalidLayout { .. })
        ));
    }
}
