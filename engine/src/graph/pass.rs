//! A pass is a value that names what it reads and writes and records its
//! commands. It never inserts barriers or queries itself: the executor does.

use crate::backend::{GpuResult, Image};
use ash::vk;
use std::ops::Range;

/// How a pass uses an image; the executor maps it to layout, stage, access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    ColorTarget,
    DepthTarget,
    /// Depth and stencil tested, not written (a screen pass masked by the stencil).
    DepthRead,
    Sampled,
    TransferSrc,
    TransferDst,
}

impl Usage {
    pub fn writes(self) -> bool {
        matches!(
            self,
            Usage::ColorTarget | Usage::DepthTarget | Usage::TransferDst
        )
    }
}

/// One image (a range of its MIP levels, every layer) used one way.
pub struct Access<'a> {
    pub image: &'a Image,
    pub levels: Range<u32>,
    pub usage: Usage,
}

impl<'a> Access<'a> {
    pub fn whole(image: &'a Image, usage: Usage) -> Self {
        Self {
            image,
            levels: 0..image.desc.mip_levels,
            usage,
        }
    }
    pub fn level(image: &'a Image, level: u32, usage: Usage) -> Self {
        Self {
            image,
            levels: level..level + 1,
            usage,
        }
    }
}

pub trait Pass {
    /// The name in counters, labels and errors.
    fn name(&self) -> &str;
    fn accesses(&self) -> Vec<Access<'_>>;
    /// Records the pass's commands; barriers for `accesses` are in place.
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()>;
}
