//! Runs an ordered list of passes as one submission: per pass a debug label,
//! the barriers its declared accesses need, a GPU timestamp scope and a
//! pipeline-statistics query, then the pass's own commands.

use super::pass::Pass;
use super::states::ImageStates;
use crate::backend::{Commands, Device, GpuError, GpuResult, PassQueries, PassSample};
use ash::vk;
use std::ffi::CString;

/// One pass's cost in one frame.
#[derive(Clone, Debug)]
pub struct PassTiming {
    pub name: String,
    pub sample: PassSample,
}

pub struct Executor {
    device: Device,
    commands: Commands,
    queries: PassQueries,
    /// This submission's label names: kept until the next recording, since
    /// Mesa 22's command buffers keep the `pLabelName` pointer they get.
    labels: Vec<CString>,
    pub states: ImageStates,
}

impl Executor {
    pub fn new(device: &Device) -> GpuResult<Self> {
        Ok(Self {
            device: device.clone(),
            commands: Commands::new(device)?,
            queries: PassQueries::new(device, 16)?,
            labels: Vec::new(),
            states: ImageStates::default(),
        })
    }

    /// The command buffer for set-up uploads (not a frame).
    pub fn commands(&self) -> &Commands {
        &self.commands
    }

    /// Records, submits and waits for `passes`; returns each pass's timing.
    pub fn run(&mut self, passes: &[&dyn Pass]) -> GpuResult<Vec<PassTiming>> {
        if passes.len() as u32 > self.queries.capacity() {
            let bigger = PassQueries::new(&self.device, passes.len() as u32)?;
            self.wait_idle();
            self.queries = bigger;
        }
        let cmd = self.commands.begin()?;
        // The buffer was reset: nothing refers to the old names any more.
        self.labels.clear();
        self.queries.reset(cmd);
        for (index, pass) in passes.iter().enumerate() {
            let index = index as u32;
            self.begin_label(cmd, pass.name());
            let barriers = self.states.barriers(&pass.accesses());
            if !barriers.is_empty() {
                // SAFETY: barriers reference images alive for this frame.
                unsafe {
                    self.device.device.cmd_pipeline_barrier2(
                        cmd,
                        &vk::DependencyInfo::default().image_memory_barriers(&barriers),
                    )
                };
            }
            self.queries.begin(cmd, index);
            let recorded = pass.record(cmd);
            self.queries.end(cmd, index);
            self.end_label(cmd);
            recorded.map_err(|e| GpuError::InPass {
                pass: pass.name().to_owned(),
                source: Box::new(e),
            })?;
        }
        // Make every device write visible to the host reading back after
        // the fence (captures, read-back buffers).
        let to_host = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        // SAFETY: recording state; a global memory barrier has no handles.
        unsafe {
            self.device.device.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().memory_barriers(&to_host),
            )
        };
        self.commands.submit_and_wait().map_err(|e| match e {
            GpuError::DeviceLost { .. } => GpuError::DeviceLost {
                last_pass: passes
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(" → ")
                    + " (one of these)",
            },
            other => other,
        })?;
        let samples = self.queries.read(passes.len() as u32)?;
        Ok(passes
            .iter()
            .zip(samples)
            .map(|(p, sample)| PassTiming {
                name: p.name().to_string(),
                sample,
            })
            .collect())
    }

    fn begin_label(&mut self, cmd: vk::CommandBuffer, name: &str) {
        if let Some(debug) = &self.device.debug_utils {
            self.labels.push(CString::new(name).unwrap_or_default());
            let name = self.labels.last().map_or(c"", |n| n.as_c_str());
            let label = vk::DebugUtilsLabelEXT::default().label_name(name);
            // SAFETY: VK_EXT_debug_utils is enabled (debug_utils is Some);
            // the name lives in `labels` until the buffer is reset.
            unsafe { debug.cmd_begin_debug_utils_label(cmd, &label) };
        }
    }

    /// Lets the device finish everything before objects it may have used
    /// are destroyed. The fence wait already covers submitted work; this
    /// also covers whatever the driver's own threads still hold after it.
    fn wait_idle(&self) {
        // SAFETY: the queue is only used from the thread that owns the
        // executors (external synchronization of vkDeviceWaitIdle).
        let _ = unsafe { self.device.device.device_wait_idle() };
    }

    fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(debug) = &self.device.debug_utils {
            // SAFETY: matches begin_label in the same command buffer.
            unsafe { debug.cmd_end_debug_utils_label(cmd) };
        }
    }
}

impl Drop for Executor {
    fn drop(&mut self) {
        // Before the command pool and query pools go (fields drop after).
        self.wait_idle();
    }
}
