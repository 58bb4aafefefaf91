//! GPU timestamps and pipeline statistics, one scope per pass. Slots come
//! from the pass index (2 timestamps, 1 statistics query each), never from
//! hand-numbered constants.

use super::device::Device;
use super::error::{GpuResult, VkContext};
use ash::vk;

pub struct PassQueries {
    device: Device,
    timestamps: vk::QueryPool,
    statistics: vk::QueryPool,
    capacity: u32,
}

/// What one pass cost on the GPU in one frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassSample {
    pub gpu_ms: f64,
    pub fragment_invocations: u64,
}

impl PassQueries {
    pub fn new(device: &Device, passes: u32) -> GpuResult<Self> {
        let capacity = passes.max(1);
        let ts_info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2 * capacity);
        let stats_info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::PIPELINE_STATISTICS)
            .query_count(capacity)
            .pipeline_statistics(vk::QueryPipelineStatisticFlags::FRAGMENT_SHADER_INVOCATIONS);
        // SAFETY: valid device; both pools are destroyed in Drop.
        let (timestamps, statistics) = unsafe {
            let timestamps = device
                .device
                .create_query_pool(&ts_info, None)
                .vk("vkCreateQueryPool")?;
            match device.device.create_query_pool(&stats_info, None) {
                Ok(statistics) => (timestamps, statistics),
                Err(e) => {
                    device.device.destroy_query_pool(timestamps, None);
                    return Err(e).vk("vkCreateQueryPool");
                }
            }
        };
        Ok(Self {
            device: device.clone(),
            timestamps,
            statistics,
            capacity,
        })
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub fn reset(&self, cmd: vk::CommandBuffer) {
        // SAFETY: called outside a render pass at the start of the frame.
        unsafe {
            let d = &self.device.device;
            d.cmd_reset_query_pool(cmd, self.timestamps, 0, 2 * self.capacity);
            d.cmd_reset_query_pool(cmd, self.statistics, 0, self.capacity);
        }
    }

    pub fn begin(&self, cmd: vk::CommandBuffer, pass: u32) {
        // SAFETY: `pass < capacity` (the executor sizes the pools from its
        // pass list) and the queries were reset this frame.
        unsafe {
            let d = &self.device.device;
            // ALL_COMMANDS, not TOP_OF_PIPE: lavapipe flushes queued work
            // only before a timestamp of a later stage, so this keeps the
            // previous pass's rasterisation out of this pass's scope.
            d.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.timestamps,
                2 * pass,
            );
            d.cmd_begin_query(cmd, self.statistics, pass, vk::QueryControlFlags::empty());
        }
    }

    pub fn end(&self, cmd: vk::CommandBuffer, pass: u32) {
        // SAFETY: matches `begin` for the same pass.
        unsafe {
            let d = &self.device.device;
            d.cmd_end_query(cmd, self.statistics, pass);
            d.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                self.timestamps,
                2 * pass + 1,
            );
        }
    }

    /// Reads the first `passes` scopes after the frame's fence signalled.
    pub fn read(&self, passes: u32) -> GpuResult<Vec<PassSample>> {
        let n = passes.min(self.capacity) as usize;
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; 2 * n];
        let mut stats = vec![[0u64; 1]; n];
        // SAFETY: the frame that wrote these queries has completed (caller
        // waited on its fence); WAIT makes the read block otherwise.
        unsafe {
            let d = &self.device.device;
            d.get_query_pool_results(
                self.timestamps,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
            .vk("vkGetQueryPoolResults(timestamps)")?;
            d.get_query_pool_results(
                self.statistics,
                0,
                &mut stats,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
            .vk("vkGetQueryPoolResults(statistics)")?;
        }
        let period_ns = self.device.timestamp_period();
        Ok((0..n)
            .map(|i| PassSample {
                gpu_ms: ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period_ns * 1e-6,
                fragment_invocations: stats[i][0],
            })
            .collect())
    }
}

impl Drop for PassQueries {
    fn drop(&mut self) {
        // SAFETY: no frame using the pools is pending when they are dropped.
        unsafe {
            self.device.device.destroy_query_pool(self.timestamps, None);
            self.device.device.destroy_query_pool(self.statistics, None);
        }
    }
}
