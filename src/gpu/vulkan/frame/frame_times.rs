//! The GPU time of each frame's work (`FrameRunner::process`), from the timestamps of its
//! submissions (gpu/vulkan/device/gpu_timer.rs), read once each submission's fence has been
//! waited for: normally at the next frame, so measuring never waits for the GPU. A frame of
//! more views than one submission holds adds up its submissions.

use crate::gpu::vulkan::device::{GpuDevice, GpuTimer};
use ash::vk;
use std::time::Duration;

/// Frames' times kept for the layer to take (a layer that takes none keeps no more).
const KEPT: usize = 1024;

#[derive(Default)]
pub struct FrameTimes {
    /// None where the queue writes no timestamps (or the pool could not be made).
    timer: Option<GpuTimer>,
    /// The frame being recorded (counts `process` calls).
    frame: u64,
    /// The frame the submission in flight belongs to.
    in_flight: u64,
    /// Measured submissions: (frame, time), in order.
    times: Vec<(u64, Duration)>,
}

impl FrameTimes {
    /// Times on `gpu`'s queue, where it writes timestamps.
    pub fn new(gpu: &GpuDevice) -> FrameTimes {
        FrameTimes {
            timer: GpuTimer::new(gpu).ok().flatten(),
            ..FrameTimes::default()
        }
    }

    /// A new frame's submissions follow.
    pub fn next_frame(&mut self) {
        self.frame += 1;
    }

    /// At the start of a submission's commands.
    pub fn record_start(&mut self, gpu: &GpuDevice, cmd: vk::CommandBuffer) {
        if let Some(t) = &mut self.timer {
            t.record_start(gpu, cmd);
        }
    }

    /// At the end of a submission's commands.
    pub fn record_end(&mut self, gpu: &GpuDevice, cmd: vk::CommandBuffer) {
        if let Some(t) = &mut self.timer {
            t.record_end(gpu, cmd);
            self.in_flight = self.frame;
        }
    }

    /// After the last submission's fence was waited for: its time.
    pub fn read(&mut self, gpu: &GpuDevice) {
        let Some(time) = self.timer.as_mut().and_then(|t| t.read(gpu)) else {
            return;
        };
        match self.times.last_mut() {
            Some((frame, sum)) if *frame == self.in_flight => *sum += time,
            _ => self.times.push((self.in_flight, time)),
        }
        if self.times.len() > KEPT {
            self.times.remove(0);
        }
    }

    /// The GPU times of the frames whose submissions have all been read, oldest first.
    pub fn take(&mut self) -> Vec<Duration> {
        let done = self.times.partition_point(|&(f, _)| f < self.frame);
        self.times.drain(..done).map(|(_, t)| t).collect()
    }

    /// Destroys the timer's pool; the GPU must be done with the last submission.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        if let Some(mut t) = self.timer.take() {
            t.destroy(gpu);
        }
    }
}
