//! One array element of a host-written image lent to one writer — a
//! decoder on another thread — so decoded texels land in the texture the
//! sampler reads, with no staging copy. The element stays lent (no second
//! writer) until the [`HostElement`] drops; keeping the device away from
//! an element while it is written is the lender's part (PEM playback lends
//! only slots no recorded frame reads).

use super::error::{GpuError, GpuResult};
use super::image::Image;
use super::upload::texel_size;
use std::ptr::NonNull;
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// Where one level of one layer of the element lies in mapped memory.
#[derive(Clone, Copy, Debug)]
struct Level {
    offset: usize,
    row_pitch: usize,
    /// Tight bytes of a row, and rows.
    row: usize,
    rows: usize,
}

/// The mapped memory's start.
struct Mapped(NonNull<u8>);

// SAFETY: the pointer is into the mapped allocation of the image the
// owning HostElement keeps alive (its Arc) wherever it goes; writes
// through it stay inside that element's subresources, which the `lent`
// flag gives to one HostElement at a time, so no other Rust code writes
// them meanwhile.
unsafe impl Send for Mapped {}

pub struct HostElement {
    image: Arc<Image>,
    element: u32,
    base: Mapped,
    /// `levels[level * element_layers + layer]`.
    levels: Vec<Level>,
    /// Texel components (2 bytes each, so aligned for f16 views).
    scratch: Vec<u16>,
    /// A level with padded rows, written into scratch, copied on flush.
    pending: Option<Level>,
}

impl HostElement {
    /// Lends array element `element` of `image` (host-written): fails when
    /// the image is not host-written or the element is lent already.
    pub fn lend(image: &Arc<Image>, element: u32) -> GpuResult<Self> {
        let desc = image.desc;
        let (Some(base), Some(flag)) = (image.mapped_ptr(), image.lent.get(element as usize))
        else {
            return Err(GpuError::Invalid(format!(
                "element {element} of a {desc:?} cannot be written by the host"
            )));
        };
        if flag.swap(true, Ordering::Acquire) {
            return Err(GpuError::Invalid(format!(
                "element {element} of a {desc:?} is already being written"
            )));
        }
        let texel = texel_size(desc.format).unwrap_or(0) as usize;
        let layers = desc.element_layers();
        let mut levels = Vec::with_capacity((desc.mip_levels * layers) as usize);
        for level in 0..desc.mip_levels {
            for layer in 0..layers {
                let l = image.subresource_layout(level, element * layers + layer);
                let (w, h) = desc.mip_extent(level);
                levels.push(Level {
                    offset: l.offset as usize,
                    row_pitch: l.row_pitch as usize,
                    row: w as usize * texel,
                    rows: h as usize,
                });
            }
        }
        let element = Self {
            image: image.clone(),
            element,
            base: Mapped(base),
            levels,
            scratch: Vec::new(),
            pending: None,
        };
        // Every level must lie inside the mapping, rows no wider than their
        // pitch, offsets aligned for 2-byte texel components: checked once
        // here, so the writes below need no checks.
        let len = image.mapped_len();
        let fits = element.levels.iter().all(|l| {
            l.row <= l.row_pitch
                && l.offset % 8 == 0
                && l.rows > 0
                && l.offset + l.row_pitch * (l.rows - 1) + l.row <= len
        });
        if texel == 0 || !fits {
            return Err(GpuError::Invalid(format!(
                "element {} of a {desc:?}: its layout leaves the mapped memory",
                element.element
            )));
        }
        Ok(element)
    }

    /// The bytes of level `level` of the element's layer `layer` (a cube
    /// face), rows tight: the image's own memory where its rows are tight,
    /// else scratch copied into the padded rows at the next call, at
    /// [`Self::flush`] or on drop. `bytes` must be the level's tight size.
    pub fn level_mut(&mut self, layer: u32, level: u32, bytes: usize) -> Option<&mut [u8]> {
        self.flush();
        let layers = self.image.desc.element_layers();
        if layer >= layers {
            return None;
        }
        let l = *self.levels.get((level * layers + layer) as usize)?;
        if bytes != l.row * l.rows {
            return None;
        }
        if l.row == l.row_pitch && bytes % 2 == 0 {
            // SAFETY: the level lies inside the mapped allocation (checked in
            // `lend`), belongs to this lent element, and `&mut self` keeps
            // this the only slice of it.
            return Some(unsafe {
                std::slice::from_raw_parts_mut(self.base.0.as_ptr().add(l.offset), bytes)
            });
        }
        self.scratch.resize(bytes.div_ceil(2), 0);
        self.pending = Some(l);
        let scratch: &mut [u8] = bytemuck::cast_slice_mut(&mut self.scratch[..]);
        Some(&mut scratch[..bytes])
    }

    /// Copies a padded level written into scratch to its rows.
    pub fn flush(&mut self) {
        let Some(l) = self.pending.take() else {
            return;
        };
        let scratch: &[u8] = bytemuck::cast_slice(&self.scratch[..]);
        for (y, src) in scratch.chunks_exact(l.row).take(l.rows).enumerate() {
            // SAFETY: as in `level_mut`; row y lies inside the level
            // (checked in `lend`) and no slice of the element is alive.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    src.as_ptr(),
                    self.base.0.as_ptr().add(l.offset + y * l.row_pitch),
                    l.row,
                );
            }
        }
    }

    /// The array element this writes.
    pub fn element(&self) -> u32 {
        self.element
    }

    /// Its subresources: every (level, layer) a full write covers.
    pub fn subresources(&self) -> usize {
        self.levels.len()
    }
}

impl Drop for HostElement {
    fn drop(&mut self) {
        self.flush();
        if let Some(flag) = self.image.lent.get(self.element as usize) {
            flag.store(false, Ordering::Release);
        }
    }
}
