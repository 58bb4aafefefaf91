//! Typed reads of glTF accessors, each checked against its buffer view and
//! buffer first (the `gltf` crate's own reader panics on some malformed
//! files: a stride shorter than an element, a count of zero).

use std::path::Path;

use gltf::accessor::{DataType, Dimensions};

use crate::scene::error::SceneError;

/// The file being read and its buffers, for reads and error messages.
pub(super) struct Source<'a> {
    pub path: &'a Path,
    pub buffers: &'a [Vec<u8>],
}

impl Source<'_> {
    pub fn err(&self, location: &str, message: impl Into<String>) -> SceneError {
        SceneError::gltf(self.path, location, message)
    }

    /// One byte slice per element of `accessor`, after checking that its type
    /// is one of `expected` (named `what` in messages) and that every element
    /// lies inside its buffer view and buffer.
    fn elements<'s>(
        &'s self,
        at: &str,
        accessor: &gltf::Accessor,
        expected: &[(DataType, Dimensions)],
        what: &str,
    ) -> Result<impl Iterator<Item = &'s [u8]> + 's, SceneError> {
        let at = format!("{at}, accessor {}", accessor.index());
        let kind = (accessor.data_type(), accessor.dimensions());
        if !expected.contains(&kind) {
            return Err(self.err(
                &at,
                format!("is {:?} {:?} (expected {what})", kind.0, kind.1),
            ));
        }
        if accessor.sparse().is_some() {
            return Err(self.err(&at, "is sparse (expected a plain accessor)"));
        }
        let Some(view) = accessor.view() else {
            return Err(self.err(&at, "has no bufferView (expected data)"));
        };
        let count = accessor.count();
        let size = accessor.size();
        let stride = view.stride().unwrap_or(size);
        if count == 0 || stride < size {
            return Err(self.err(
                &at,
                format!(
                    "count {count}, element size {size}, stride {stride} \
                     (expected a count ≥ 1 and a stride ≥ the element size)"
                ),
            ));
        }
        // Bytes from the view's start to the end of the last element.
        let span = (count - 1)
            .checked_mul(stride)
            .and_then(|n| n.checked_add(accessor.offset()))
            .and_then(|n| n.checked_add(size));
        if span.is_none_or(|span| span > view.length()) {
            return Err(self.err(
                &at,
                format!(
                    "{count} elements from offset {} overrun buffer view {} \
                     ({} bytes; expected them inside it)",
                    accessor.offset(),
                    view.index(),
                    view.length()
                ),
            ));
        }
        let data = &self.buffers[view.buffer().index()];
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|end| end > data.len()) {
            return Err(self.err(
                &format!("buffer view {}", view.index()),
                format!(
                    "{} bytes from offset {} overrun buffer {} ({} bytes; expected them inside it)",
                    view.length(),
                    view.offset(),
                    view.buffer().index(),
                    data.len()
                ),
            ));
        }
        let start = view.offset() + accessor.offset();
        Ok((0..count).map(move |i| &data[start + i * stride..][..size]))
    }

    /// A VEC3 float attribute (positions, normals).
    pub fn vec3(&self, at: &str, accessor: &gltf::Accessor) -> Result<Vec<[f32; 3]>, SceneError> {
        let f32s = |e: &[u8]| [0, 4, 8].map(|k| f32_at(e, k));
        Ok(self
            .elements(
                at,
                accessor,
                &[(DataType::F32, Dimensions::Vec3)],
                "F32 Vec3",
            )?
            .map(f32s)
            .collect())
    }

    /// A VEC2 texture-coordinate attribute: float, or normalised unsigned
    /// bytes or shorts.
    pub fn vec2(&self, at: &str, accessor: &gltf::Accessor) -> Result<Vec<[f32; 2]>, SceneError> {
        let kinds = [
            (DataType::F32, Dimensions::Vec2),
            (DataType::U8, Dimensions::Vec2),
            (DataType::U16, Dimensions::Vec2),
        ];
        let what = "F32 Vec2, or normalized U8 or U16 Vec2";
        let data_type = accessor.data_type();
        if data_type != DataType::F32 && !accessor.normalized() {
            return Err(self.err(
                &format!("{at}, accessor {}", accessor.index()),
                format!("is {data_type:?} but not normalized (expected {what})"),
            ));
        }
        let elements = self.elements(at, accessor, &kinds, what)?;
        Ok(elements
            .map(|e| match data_type {
                DataType::U8 => [0, 1].map(|k| f32::from(e[k]) / 255.0),
                DataType::U16 => [0, 2].map(|k| f32::from(u16_at(e, k)) / 65535.0),
                _ => [0, 4].map(|k| f32_at(e, k)),
            })
            .collect())
    }

    /// A SCALAR unsigned-integer index accessor.
    pub fn indices(&self, at: &str, accessor: &gltf::Accessor) -> Result<Vec<u32>, SceneError> {
        let kinds = [
            (DataType::U8, Dimensions::Scalar),
            (DataType::U16, Dimensions::Scalar),
            (DataType::U32, Dimensions::Scalar),
        ];
        let data_type = accessor.data_type();
        let elements = self.elements(at, accessor, &kinds, "U8, U16 or U32 Scalar")?;
        Ok(elements
            .map(|e| match data_type {
                DataType::U8 => u32::from(e[0]),
                DataType::U16 => u32::from(u16_at(e, 0)),
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            })
            .collect())
    }
}

fn f32_at(bytes: &[u8], k: usize) -> f32 {
    f32::from_le_bytes([bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]])
}

fn u16_at(bytes: &[u8], k: usize) -> u16 {
    u16::from_le_bytes([bytes[k], bytes[k + 1]])
}
