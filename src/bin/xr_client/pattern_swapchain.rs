//! A runtime swapchain filled with the test pattern by copies from a staging buffer (no shaders).

use ash::vk::{self, Handle};
use openxr as xr;

use crate::error::{Context, Result};
use crate::gpu::Gpu;
use crate::pattern::{image_bytes, LayerContent, Rows};
use crate::swapchain_format::SwapchainFormat;
use crate::timing::Calls;
use crate::untouched::Untouched;

pub struct PatternSwapchain {
    pub handle: xr::Swapchain<xr::Vulkan>,
    images: Vec<vk::Image>,
    pub width: u32,
    pub height: u32,
    layers: u32,
    staging: vk::Buffer,
    memory: vk::DeviceMemory,
    /// The device that owns `staging`; a clone of the Gpu's (ash devices are plain tables).
    device: ash::Device,
    /// With --check-untouched: the pattern's bytes, a buffer to read images back into, and for
    /// each image the frame that last wrote it.
    check: Option<Check>,
    /// With --timing: the wall times of acquire, wait and release.
    calls: Calls,
}

struct Check {
    pattern: Vec<u8>,
    readback: vk::Buffer,
    memory: vk::DeviceMemory,
    log: Untouched,
}

impl PatternSwapchain {
    pub fn new(
        session: &xr::Session<xr::Vulkan>,
        gpu: &Gpu,
        format: SwapchainFormat,
        (width, height): (u32, u32),
        content: &[LayerContent],
        check: bool,
    ) -> Result<PatternSwapchain> {
        let read_back = if check {
            xr::SwapchainUsageFlags::TRANSFER_SRC
        } else {
            xr::SwapchainUsageFlags::EMPTY
        };
        let handle = session
            .create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: xr::SwapchainUsageFlags::COLOR_ATTACHMENT
                    | xr::SwapchainUsageFlags::TRANSFER_DST
                    | read_back,
                format: format.vk.as_raw() as _,
                sample_count: 1,
                width,
                height,
                face_count: 1,
                array_size: content.len() as u32,
                mip_count: 1,
            })
            .ctx(&format!(
                "xrCreateSwapchain ({} {width}x{height}, arraySize {})",
                format.name,
                content.len()
            ))?;
        let images = handle
            .enumerate_images()
            .ctx("xrEnumerateSwapchainImages")?;
        let bytes = image_bytes(format, (width, height), content, Rows::TopFirst);
        let (staging, memory) = create_staging(gpu, &bytes, vk::BufferUsageFlags::TRANSFER_SRC)?;
        let check = if check {
            let (readback, memory) =
                create_staging(gpu, &bytes, vk::BufferUsageFlags::TRANSFER_DST)?;
            Some(Check {
                log: Untouched::new(images.len()),
                pattern: bytes,
                readback,
                memory,
            })
        } else {
            None
        };
        Ok(PatternSwapchain {
            check,
            calls: Calls::default(),
            handle,
            images: images.into_iter().map(vk::Image::from_raw).collect(),
            width,
            height,
            layers: content.len() as u32,
            staging,
            memory,
            device: gpu.device.clone(),
        })
    }

    /// Records the wall times of its OpenXR calls from now on when `on` (--timing).
    pub fn timed(mut self, on: bool) -> PatternSwapchain {
        self.calls = Calls::new(on);
        self
    }

    pub fn calls(&self) -> &Calls {
        &self.calls
    }

    /// Acquires and waits for the next image; returns its index.
    pub fn acquire(&mut self) -> Result<u32> {
        let handle = &mut self.handle;
        let index = self
            .calls
            .time("xrAcquireSwapchainImage", || handle.acquire_image())
            .ctx("xrAcquireSwapchainImage")?;
        self.calls
            .time("xrWaitSwapchainImage", || {
                handle.wait_image(xr::Duration::INFINITE)
            })
            .ctx("xrWaitSwapchainImage")?;
        Ok(index)
    }

    pub fn release(&mut self) -> Result<()> {
        let handle = &mut self.handle;
        self.calls
            .time("xrReleaseSwapchainImage", || handle.release_image())
            .ctx("xrReleaseSwapchainImage")
    }

    /// Every texel of every layer, tightly packed layer after layer in the buffer.
    fn whole_image_copy(&self) -> vk::BufferImageCopy {
        vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .layer_count(self.layers),
            )
            .image_extent(vk::Extent3D {
                width: self.width,
                height: self.height,
                depth: 1,
            })
    }

    /// Records the copy of the pattern into image `index`, leaving it in
    /// COLOR_ATTACHMENT_OPTIMAL, the layout XR_KHR_vulkan_enable2 expects at release.
    pub fn record_upload(&self, device: &ash::Device, cmd: vk::CommandBuffer, index: u32) {
        let image = self.images[index as usize];
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(self.layers);
        // The old contents are not needed (every texel is overwritten) unless read back first.
        let to_transfer = if self.record_readback(device, cmd, index, range) {
            barrier(
                image,
                range,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            )
            .src_access_mask(vk::AccessFlags::TRANSFER_READ)
        } else {
            barrier(
                image,
                range,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            )
        }
        .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE);
        let copy = self.whole_image_copy();
        record_transfer_write(device, cmd, image, range, to_transfer, || {
            // SAFETY: `cmd` is recording; the image was acquired and waited for, the staging
            // buffer holds width x height x layers texels in this format, layer after layer.
            unsafe {
                device.cmd_copy_buffer_to_image(
                    cmd,
                    self.staging,
                    image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[copy],
                )
            };
        });
    }
}

/// Records `write` (transfer commands into `image` in TRANSFER_DST_OPTIMAL) after the barrier
/// `to_transfer`, then the transition to COLOR_ATTACHMENT_OPTIMAL, the layout
/// XR_KHR_vulkan_enable2 expects at release.
pub fn record_transfer_write(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    to_transfer: vk::ImageMemoryBarrier<'_>,
    write: impl FnOnce(),
) {
    let to_colour = barrier(
        image,
        range,
        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    )
    .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
    .dst_access_mask(
        vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
    );
    // SAFETY: `cmd` is recording and the image is the client's to write (acquired, waited).
    unsafe {
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TOP_OF_PIPE | vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[to_transfer],
        );
    }
    write();
    // SAFETY: as above.
    unsafe {
        device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[to_colour],
        );
    }
}

impl PatternSwapchain {
    /// With --check-untouched and an image written before: records the copy of the image as the
    /// runtime left it (COLOR_ATTACHMENT_OPTIMAL after acquire) into the readback buffer.
    fn record_readback(
        &self,
        device: &ash::Device,
        cmd: vk::CommandBuffer,
        index: u32,
        range: vk::ImageSubresourceRange,
    ) -> bool {
        let Some(check) = self.check.as_ref().filter(|c| c.log.written_before(index)) else {
            return false;
        };
        let image = self.images[index as usize];
        let to_source = barrier(
            image,
            range,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )
        .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
        .dst_access_mask(vk::AccessFlags::TRANSFER_READ);
        let copy = self.whole_image_copy();
        // SAFETY: `cmd` is recording; the image is acquired and the readback buffer holds
        // exactly the image's texels (the pattern's size).
        unsafe {
            device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[to_source],
            );
            device.cmd_copy_image_to_buffer(
                cmd,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                check.readback,
                &[copy],
            );
        }
        true
    }

    /// After the upload of `frame` into image `index` ran: compares what was read back (the
    /// image as the client last left it, plus whatever happened after) with the pattern.
    pub fn finish_check(&mut self, index: u32, frame: u32) {
        let device = &self.device;
        let Some(check) = self.check.as_mut() else {
            return;
        };
        let same = check.log.written_before(index).then(|| {
            let len = check.pattern.len();
            // SAFETY: host-coherent memory of `len` bytes, written by a finished submission.
            unsafe {
                device
                    .map_memory(check.memory, 0, len as u64, vk::MemoryMapFlags::empty())
                    .map(|p| {
                        let same = std::slice::from_raw_parts(p.cast::<u8>(), len) == check.pattern;
                        device.unmap_memory(check.memory);
                        same
                    })
                    .unwrap_or(false)
            }
        });
        check.log.record(index, frame, same);
    }

    /// With --check-untouched: the frames whose image had changed so far.
    pub fn modified(&self) -> usize {
        self.check.as_ref().map_or(0, |c| c.log.modified.len())
    }

    /// (images checked, frames whose image had changed).
    pub fn check_result(&self) -> (u32, Vec<u32>) {
        self.check
            .as_ref()
            .map_or((0, Vec::new()), |c| (c.log.checked, c.log.modified.clone()))
    }
}

impl Drop for PatternSwapchain {
    fn drop(&mut self) {
        // SAFETY: the buffers are the client's and no submission using them is pending
        // (every submission is waited for).
        unsafe {
            self.device.destroy_buffer(self.staging, None);
            self.device.free_memory(self.memory, None);
            if let Some(check) = &self.check {
                self.device.destroy_buffer(check.readback, None);
                self.device.free_memory(check.memory, None);
            }
        }
    }
}

pub fn barrier<'a>(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
) -> vk::ImageMemoryBarrier<'a> {
    vk::ImageMemoryBarrier::default()
        .image(image)
        .subresource_range(range)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
}

fn create_staging(
    gpu: &Gpu,
    bytes: &[u8],
    usage: vk::BufferUsageFlags,
) -> Result<(vk::Buffer, vk::DeviceMemory)> {
    let device = &gpu.device;
    let info = vk::BufferCreateInfo::default()
        .size(bytes.len() as u64)
        .usage(usage);
    // SAFETY: plain object creation on a live device; the mapping covers exactly `bytes.len()`
    // bytes of host-coherent memory, so no flush is needed.
    unsafe {
        let buffer = device.create_buffer(&info, None).ctx("vkCreateBuffer")?;
        let reqs = device.get_buffer_memory_requirements(buffer);
        let alloc = vk::MemoryAllocateInfo::default()
            .allocation_size(reqs.size)
            .memory_type_index(gpu.host_memory_type(reqs.memory_type_bits)?);
        let memory = device
            .allocate_memory(&alloc, None)
            .ctx("vkAllocateMemory")?;
        device
            .bind_buffer_memory(buffer, memory, 0)
            .ctx("vkBindBufferMemory")?;
        let mapped = device
            .map_memory(memory, 0, bytes.len() as u64, vk::MemoryMapFlags::empty())
            .ctx("vkMapMemory")?;
        std::ptr::copy_nonoverlapping(bytes.as_ptr(), mapped.cast::<u8>(), bytes.len());
        device.unmap_memory(memory);
        Ok((buffer, memory))
    }
}
