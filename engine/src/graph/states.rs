//! Tracks the layout and last access of every image level across passes and
//! frames, and turns a pass's declared accesses into the barriers it needs.

use super::pass::{Access, Usage};
use ash::vk;
use std::collections::HashMap;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LevelState {
    layout: vk::ImageLayout,
    stage: vk::PipelineStageFlags2,
    access: vk::AccessFlags2,
    wrote: bool,
}

const UNTOUCHED: LevelState = LevelState {
    layout: vk::ImageLayout::UNDEFINED,
    stage: vk::PipelineStageFlags2::NONE,
    access: vk::AccessFlags2::NONE,
    wrote: false,
};

fn target_state(usage: Usage) -> LevelState {
    use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
    let (layout, stage, access) = match usage {
        Usage::ColorTarget => (
            L::COLOR_ATTACHMENT_OPTIMAL,
            S::COLOR_ATTACHMENT_OUTPUT,
            A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
        ),
        Usage::DepthTarget => (
            L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
        ),
        Usage::DepthRead => (
            L::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
            S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            A::DEPTH_STENCIL_ATTACHMENT_READ,
        ),
        Usage::Sampled => (
            L::SHADER_READ_ONLY_OPTIMAL,
            S::FRAGMENT_SHADER,
            A::SHADER_SAMPLED_READ,
        ),
        Usage::TransferSrc => (L::TRANSFER_SRC_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_READ),
        Usage::TransferDst => (L::TRANSFER_DST_OPTIMAL, S::ALL_TRANSFER, A::TRANSFER_WRITE),
    };
    LevelState {
        layout,
        stage,
        access,
        wrote: usage.writes(),
    }
}

/// [`target_state`], but a host-written image is sampled in GENERAL: the
/// host writes it between frames, which only GENERAL allows.
fn wanted_state(desc: &crate::backend::ImageDesc, usage: Usage) -> LevelState {
    let mut state = target_state(usage);
    if desc.host_written && usage == Usage::Sampled {
        state.layout = vk::ImageLayout::GENERAL;
    }
    state
}

/// Keyed by [`Image::uid`](crate::backend::Image::uid), not by handle: an
/// image dropped without [`ImageStates::forget`] must not lend its layout
/// to a new image that gets the same handle.
#[derive(Default)]
pub struct ImageStates {
    levels: HashMap<u64, Vec<LevelState>>,
}

impl ImageStates {
    /// Declares that set-up work (an upload) left the whole image in the
    /// state `usage` implies, so the first pass needs no transition.
    pub fn assume(&mut self, image: &crate::backend::Image, usage: Usage) {
        let mut state = wanted_state(&image.desc, usage);
        state.wrote = true; // the upload's write is made visible by the next barrier
        self.levels
            .insert(image.uid, vec![state; image.desc.mip_levels as usize]);
    }

    /// Drops what is known of an image about to be destroyed (keeps the
    /// map small; a new image starts from its initial layout either way).
    pub fn forget(&mut self, image: &crate::backend::Image) {
        self.levels.remove(&image.uid);
    }

    /// The barriers that make `accesses` safe after everything recorded so
    /// far, updating the tracked states.
    pub fn barriers(&mut self, accesses: &[Access]) -> Vec<vk::ImageMemoryBarrier2<'static>> {
        let mut barriers = Vec::new();
        for a in accesses {
            let desc = a.image.desc;
            let levels = self.levels.entry(a.image.uid).or_insert_with(|| {
                let initial = LevelState {
                    layout: desc.initial_layout(),
                    ..UNTOUCHED
                };
                vec![initial; desc.mip_levels as usize]
            });
            let wanted = wanted_state(&desc, a.usage);
            for level in a.levels.clone() {
                let Some(current) = levels.get_mut(level as usize) else {
                    continue;
                };
                let hazard = current.wrote || a.usage.writes();
                if current.layout == wanted.layout && !hazard {
                    // Read after read: widen the scope for the next writer.
                    current.stage |= wanted.stage;
                    current.access |= wanted.access;
                    continue;
                }
                barriers.push(
                    vk::ImageMemoryBarrier2::default()
                        .src_stage_mask(current.stage)
                        .src_access_mask(if current.wrote {
                            current.access
                        } else {
                            vk::AccessFlags2::NONE
                        })
                        .dst_stage_mask(wanted.stage)
                        .dst_access_mask(wanted.access)
                        .old_layout(current.layout)
                        .new_layout(wanted.layout)
                        .image(a.image.raw)
                        .subresource_range(vk::ImageSubresourceRange {
                            aspect_mask: desc.aspect(),
                            base_mip_level: level,
                            level_count: 1,
                            base_array_layer: 0,
                            layer_count: desc.layers(),
                        }),
                );
                *current = wanted;
            }
        }
        barriers
    }
}
