//! One command buffer with its pool and fence: how the engine's recorded work is submitted, on
//! the engine's own queue (the CLI) or on an app's queue inside the OpenXR calls that allow it
//! (the layer). Only this module creates, submits and waits on these objects.

use super::error::{GpuError, VkResultExt};
use super::gpu_device::GpuDevice;
use ash::vk;

pub struct Commands {
    pool: vk::CommandPool,
    /// The command buffer to record into between `begin` and `submit`.
    pub cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// A submission whose fence has not been waited for.
    in_flight: bool,
    /// Submissions made, and how many of them are known to have finished.
    submitted: u64,
    finished: u64,
}

impl Commands {
    pub fn new(gpu: &GpuDevice) -> Result<Commands, GpuError> {
        let mut c = Commands {
            pool: vk::CommandPool::null(),
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            in_flight: false,
            submitted: 0,
            finished: 0,
        };
        if let Err(e) = c.create(gpu) {
            // Nothing was submitted: the wait in destroy cannot fail.
            let _ = c.destroy(gpu);
            return Err(e);
        }
        Ok(c)
    }

    fn create(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        let d = &gpu.device;
        let info = vk::CommandPoolCreateInfo::default()
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER)
            .queue_family_index(gpu.queue_family);
        // SAFETY: valid create infos on a valid device; the objects are ours.
        unsafe {
            self.pool = d
                .create_command_pool(&info, None)
                .vk("vkCreateCommandPool")?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(self.pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            self.cmd = d
                .allocate_command_buffers(&alloc)
                .vk("vkAllocateCommandBuffers")?[0];
            self.fence = d
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .vk("vkCreateFence")?;
        }
        Ok(())
    }

    /// Waits (at most `timeout_ns`) for the last submission, so what it used can be reused.
    pub fn wait(&mut self, gpu: &GpuDevice, timeout_ns: u64) -> Result<(), GpuError> {
        if self.in_flight {
            // SAFETY: the fence is ours and was submitted.
            unsafe {
                gpu.device
                    .wait_for_fences(&[self.fence], true, timeout_ns)
                    .vk("vkWaitForFences")?;
                gpu.device.reset_fences(&[self.fence]).vk("vkResetFences")?;
            }
            self.in_flight = false;
        }
        self.finished = self.submitted;
        Ok(())
    }

    /// The number the next submission will have (the first is 1).
    pub fn next_submission(&self) -> u64 {
        self.submitted + 1
    }

    /// Submissions up to this number have finished (known from the last wait).
    pub fn finished_through(&self) -> u64 {
        self.finished
    }

    /// Begins recording a one-time submission; the previous one must have been waited for.
    pub fn begin(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        if self.in_flight {
            return Err(GpuError::Unsupported(
                "command buffer still in flight".into(),
            ));
        }
        let info = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: cmd is not pending (its last submission was waited for, checked above).
        unsafe { gpu.device.begin_command_buffer(self.cmd, &info) }.vk("vkBeginCommandBuffer")
    }

    /// Ends recording and submits on the device's queue with the fence.
    pub fn submit(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        let cmds = [self.cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // An app's queue: never at once with a runtime call the layer forwards that may submit.
        let _queue = gpu.is_the_apps().then(super::app_queue::hold);
        // SAFETY: recorded since `begin`; the caller is entitled to use the queue now (its own,
        // or an app's inside an OpenXR call that gives the runtime the queue, and the lock).
        unsafe {
            gpu.device
                .end_command_buffer(self.cmd)
                .vk("vkEndCommandBuffer")?;
            gpu.device
                .queue_submit(gpu.queue, &submit, self.fence)
                .vk("vkQueueSubmit")?;
        }
        self.in_flight = true;
        self.submitted += 1;
        Ok(())
    }

    /// Waits for the GPU and destroys the objects (null handles are ignored). When the GPU
    /// does not finish within the wait, the objects it may still use are left alive and the
    /// error returned.
    pub fn destroy(&mut self, gpu: &GpuDevice) -> Result<(), GpuError> {
        self.wait(gpu, 5_000_000_000)?;
        // SAFETY: our own objects, no longer in use after the wait.
        unsafe {
            gpu.device.destroy_fence(self.fence, None);
            gpu.device.destroy_command_pool(self.pool, None);
        }
        self.fence = vk::Fence::null();
        self.pool = vk::CommandPool::null();
        self.cmd = vk::CommandBuffer::null();
        Ok(())
    }
}
