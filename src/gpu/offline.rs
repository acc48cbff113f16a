//! The engine on a device of its own, for the command-line tool and the tests: upload, record,
//! submit, wait, read back.

use super::device::{DeviceOptions, GpuDevice};
use super::engine::{barrier, begin, BackgroundFrame, Engine, Placement, ViewTarget};
use super::error::{GpuError, VkResultExt};
use super::format::PixelFormat;
use crate::algorithm::params::Params;
use crate::image::RgbaImage;
use ash::vk;

pub struct OfflineEngine {
    pub(super) engine: Engine,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    // Declared last: dropped after the objects above are destroyed in Drop.
    pub gpu: GpuDevice,
}

/// The prepared background read back from the GPU (display grid, vec4 per pixel).
pub struct GpuBackground {
    pub linear: Vec<[f32; 4]>,
    pub scaled: Vec<[f32; 4]>,
}

fn words_to_bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

fn bytes_to_vec4(bytes: &[u8], n: usize) -> Vec<[f32; 4]> {
    bytes[..n * 16]
        .chunks_exact(16)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect()
}

impl OfflineEngine {
    /// The first Vulkan device (or `CONTRASTXR_VK_DEVICE`), validation per `CONTRASTXR_VK_VALIDATION`.
    pub fn new() -> Result<OfflineEngine, GpuError> {
        Self::with_options(&DeviceOptions::from_env())
    }

    pub fn with_options(options: &DeviceOptions) -> Result<OfflineEngine, GpuError> {
        let gpu = GpuDevice::create(options)?;
        let engine = Engine::new(&gpu, 4)?;
        let mut this = OfflineEngine {
            engine,
            pool: vk::CommandPool::null(),
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            gpu,
        };
        this.create_commands()?;
        Ok(this)
    }

    fn create_commands(&mut self) -> Result<(), GpuError> {
        let d = &self.gpu.device;
        let info = vk::CommandPoolCreateInfo::default()
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER)
            .queue_family_index(self.gpu.queue_family);
        // SAFETY: valid create infos on the engine's own device.
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

    pub fn device_name(&self) -> &str {
        &self.gpu.name
    }

    /// Runs `record` in the command buffer, submits it and waits.
    pub(super) fn submit(
        &self,
        record: impl FnOnce(vk::CommandBuffer) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
        let d = &self.gpu.device;
        begin(&self.gpu, self.cmd)?;
        record(self.cmd)?;
        barrier(
            &self.gpu,
            self.cmd,
            vk::PipelineStageFlags::ALL_COMMANDS,
            vk::PipelineStageFlags::HOST,
        );
        let cmds = [self.cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // SAFETY: the command buffer was recorded above; the queue is ours; we wait on the
        // fence before anything it uses is touched again.
        unsafe {
            d.end_command_buffer(self.cmd).vk("vkEndCommandBuffer")?;
            d.queue_submit(self.gpu.queue, &submit, self.fence)
                .vk("vkQueueSubmit")?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)
                .vk("vkWaitForFences")?;
            d.reset_fences(&[self.fence]).vk("vkResetFences")?;
        }
        Ok(())
    }

    /// Uploads a camera frame and makes one view bound to it; the caller destroys both.
    fn stage(
        &self,
        camera: &RgbaImage,
        region: (u32, u32),
        format: PixelFormat,
    ) -> Result<(BackgroundFrame, ViewTarget), GpuError> {
        let mut bg = self.engine.create_background(
            &self.gpu,
            (camera.width, camera.height),
            Placement::OFFLINE,
        )?;
        let uploaded = bg.upload(&camera.pixels);
        let view = uploaded.and_then(|_| {
            self.engine
                .create_view(&self.gpu, region, format, &bg, Placement::OFFLINE)
        });
        match view {
            Ok(view) => Ok((bg, view)),
            Err(e) => {
                bg.destroy(&self.gpu);
                Err(e)
            }
        }
    }

    fn release(&self, mut bg: BackgroundFrame, mut view: ViewTarget) {
        self.engine.destroy_view(&self.gpu, &mut view);
        bg.destroy(&self.gpu);
    }

    /// Enhances raw pixels of any supported format (1 or 2 u32 per pixel) against a camera frame.
    pub fn enhance_raw(
        &mut self,
        pixels: &[u32],
        region: (u32, u32),
        format: PixelFormat,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<Vec<u32>, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let words = (region.0 * region.1 * format.bytes_per_pixel() / 4) as usize;
        if pixels.len() != words {
            return Err(GpuError::Unsupported(
                "pixel data does not match the region".into(),
            ));
        }
        let (bg, mut view) = self.stage(camera, region, format)?;
        let result = view.pixels.write(&words_to_bytes(pixels)).and_then(|_| {
            self.submit(|cmd| {
                self.engine
                    .record_background(&self.gpu, cmd, &bg, &[&view], params)?;
                self.engine.record_enhance(&self.gpu, cmd, &view, params)
            })
        });
        let out = result.and_then(|_| {
            let bytes = view
                .pixels
                .mapped()
                .ok_or_else(|| GpuError::Unsupported("result buffer is not host-visible".into()))?;
            Ok(bytes[..words * 4]
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect())
        });
        self.release(bg, view);
        out
    }

    /// Enhances an 8-bit sRGB display image against a camera frame of any size.
    pub fn enhance(
        &mut self,
        display: &RgbaImage,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<RgbaImage, GpuError> {
        let words: Vec<u32> = display
            .pixels
            .iter()
            .map(|p| u32::from_le_bytes(*p))
            .collect();
        let region = (display.width, display.height);
        let out = self.enhance_raw(&words, region, PixelFormat::SRGB8, camera, params)?;
        Ok(RgbaImage {
            pixels: out.iter().map(|w| w.to_le_bytes()).collect(),
            ..display.clone()
        })
    }

    /// Runs only the background preparation and reads it back (for conformance tests).
    pub fn prepare_background(
        &mut self,
        camera: &RgbaImage,
        region: (u32, u32),
        params: &Params,
    ) -> Result<GpuBackground, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let (bg, view) = self.stage(camera, region, PixelFormat::SRGB8)?;
        let result = self.submit(|cmd| {
            self.engine
                .record_background(&self.gpu, cmd, &bg, &[&view], params)
        });
        let n = (region.0 * region.1) as usize;
        let out = result.and_then(|_| {
            let lin = view.bg_linear.mapped();
            let sc = view.bg_scaled.mapped();
            match (lin, sc) {
                (Some(l), Some(s)) => Ok(GpuBackground {
                    linear: bytes_to_vec4(l, n),
                    scaled: bytes_to_vec4(s, n),
                }),
                _ => Err(GpuError::Unsupported(
                    "background buffers are not host-visible".into(),
                )),
            }
        });
        self.release(bg, view);
        out
    }

    pub fn validation_errors(&self) -> u32 {
        self.gpu.validation_errors()
    }
}

impl Drop for OfflineEngine {
    fn drop(&mut self) {
        let d = &self.gpu.device;
        // SAFETY: every submission was waited for; these objects are ours.
        unsafe {
            let _ = d.device_wait_idle();
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
        self.engine.destroy(&self.gpu);
    }
}
