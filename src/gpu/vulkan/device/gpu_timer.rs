//! The GPU time of one submission: a timestamp at the start of its commands and one at their
//! end, both at BOTTOM_OF_PIPE, so the first is written once every command submitted before
//! it on the queue (on an app's queue, the app's frame) has finished, and the second once the
//! submission's own have: the time the submission adds to the queue. Read after its fence.

use super::error::{GpuError, VkResultExt};
use super::gpu_device::GpuDevice;
use ash::vk;
use std::time::Duration;

pub struct GpuTimer {
    pool: vk::QueryPool,
    /// The bits of a timestamp the queue family writes (timestampValidBits).
    valid: u64,
    /// Nanoseconds per tick.
    period_ns: f64,
    /// Both timestamps were recorded into a submission not read yet.
    recorded: bool,
}

impl GpuTimer {
    /// A timer for submissions on the device's queue; None where its queue family writes no
    /// timestamps.
    pub fn new(gpu: &GpuDevice) -> Result<Option<GpuTimer>, GpuError> {
        // SAFETY: physical belongs to this instance.
        let families = unsafe {
            gpu.instance
                .get_physical_device_queue_family_properties(gpu.physical)
        };
        let bits = families
            .get(gpu.queue_family as usize)
            .map_or(0, |f| f.timestamp_valid_bits);
        let period_ns = f64::from(gpu.timestamp_period());
        if bits == 0 || period_ns <= 0.0 {
            return Ok(None);
        }
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2);
        // SAFETY: a valid create info on a valid device; the pool is ours.
        let pool = unsafe { gpu.device.create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(Some(GpuTimer {
            pool,
            valid: u64::MAX >> (64 - bits.min(64)),
            period_ns,
            recorded: false,
        }))
    }

    /// Records the reset and the first timestamp: the first commands of a command buffer.
    pub fn record_start(&mut self, gpu: &GpuDevice, cmd: vk::CommandBuffer) {
        // SAFETY: cmd is recording, outside a render pass; the pool's last submission was
        // waited for (the engine submits one command buffer at a time) before this one.
        unsafe {
            gpu.device.cmd_reset_query_pool(cmd, self.pool, 0, 2);
            gpu.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                0,
            );
        }
        self.recorded = false;
    }

    /// Records the second timestamp: the last command of the command buffer.
    pub fn record_end(&mut self, gpu: &GpuDevice, cmd: vk::CommandBuffer) {
        // SAFETY: cmd is recording; query 0 was reset and written earlier in it.
        unsafe {
            gpu.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                1,
            );
        }
        self.recorded = true;
    }

    /// The recorded submission's time, once its fence has been waited for (None where nothing
    /// was recorded since the last read, or the results are not available).
    pub fn read(&mut self, gpu: &GpuDevice) -> Option<Duration> {
        if !std::mem::take(&mut self.recorded) {
            return None;
        }
        let mut ticks = [0u64; 2];
        // SAFETY: both queries were written by a submission whose fence was waited for; no
        // WAIT flag, so an unavailable result returns NOT_READY rather than blocking.
        unsafe {
            gpu.device.get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64,
            )
        }
        .ok()?;
        let ticks = (ticks[1] & self.valid).wrapping_sub(ticks[0] & self.valid) & self.valid;
        Some(Duration::from_nanos((ticks as f64 * self.period_ns) as u64))
    }

    /// Destroys the pool; the GPU must be done with the last submission that used it.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: our pool, no longer in use (the caller's contract).
        unsafe { gpu.device.destroy_query_pool(self.pool, None) };
        self.pool = vk::QueryPool::null();
    }
}
