//! The offline engine's in-place path: a region enhanced in an image of the app's format
//! through a storage view of it, as the layer does for swapchains with storage usage; beside
//! `enhance_raw` (through a buffer) so that tests can hold the two paths to each other.

use super::offline_engine::VkOffline;
use crate::algorithm::params::Params;
use crate::gpu::core::CameraRect;
use crate::gpu::core::PixelFormat;
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::device::{barrier, DeviceImage, GpuBuffer, GpuError};
use crate::gpu::vulkan::device::{
    record_first_layout, record_layout_barriers, record_region_copy, ImageRegion,
};
use crate::gpu::vulkan::frame::{can_store, storage_view};
use crate::gpu::vulkan::record::{PixelsIn, ViewShape};
use crate::image::RgbaImage;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// An image of `format` that a region can be enhanced in: storage usage, and for sRGB a
/// mutable format (its storage view is UNORM).
fn storage_capable_image(
    offline: &VkOffline,
    region: (u32, u32),
    (vk_format, format): (vk::Format, PixelFormat),
) -> Result<DeviceImage, GpuError> {
    let usage = vk::ImageUsageFlags::STORAGE
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::TRANSFER_DST
        | vk::ImageUsageFlags::COLOR_ATTACHMENT;
    let flags = match format.srgb {
        true => vk::ImageCreateFlags::MUTABLE_FORMAT | vk::ImageCreateFlags::EXTENDED_USAGE,
        false => vk::ImageCreateFlags::empty(),
    };
    DeviceImage::with_flags(&offline.gpu, region, vk_format, usage, flags)
}

impl VkOffline {
    /// `enhance_raw` in place: the raw pixels are written into an image of `vk_format`,
    /// enhanced there through a storage view, and read back.
    pub fn enhance_raw_in_place(
        &mut self,
        pixels: &[u32],
        (region, vk_format): ((u32, u32), vk::Format),
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<Vec<u32>, GpuError> {
        params.validate().map_err(GpuError::Unsupported)?;
        let format = PixelFormat::from_vk(vk_format)
            .ok_or_else(|| GpuError::Unsupported(format!("{vk_format:?}")))?;
        if !can_store(&self.gpu, format) {
            return Err(GpuError::Unsupported(format!(
                "{vk_format:?} is not enhanced in place on this device"
            )));
        }
        let bytes = u64::from(region.0 * region.1 * format.bytes_per_pixel());
        if pixels.len() as u64 * 4 != bytes {
            return Err(GpuError::Unsupported(
                "pixel data does not match the region".into(),
            ));
        }
        let mut image = storage_capable_image(self, region, (vk_format, format))?;
        let result = self.enhance_image(&image, pixels, (region, format), camera, params);
        image.destroy(&self.gpu);
        result
    }

    fn enhance_image(
        &mut self,
        image: &DeviceImage,
        pixels: &[u32],
        (region, format): ((u32, u32), PixelFormat),
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<Vec<u32>, GpuError> {
        let gpu = &self.gpu;
        let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        let size = pixels.len() as u64 * 4;
        let mut staging = GpuBuffer::new(gpu, size, usage, MemoryLocation::GpuToCpu, "staging")?;
        let bytes: Vec<u8> = pixels.iter().flat_map(|w| w.to_le_bytes()).collect();
        let storage = staging
            .write(&bytes)
            .and_then(|_| storage_view(gpu, image.raw, 0, format));
        let storage = match storage {
            Ok(v) => v,
            Err(e) => {
                staging.destroy(gpu);
                return Err(e);
            }
        };
        let result = self.run_in_place(image, storage, &staging, (region, format), camera, params);
        let out = result.and_then(|_| {
            let mapped = staging.mapped().ok_or_else(|| {
                GpuError::Unsupported("staging buffer is not host-visible".into())
            })?;
            Ok(mapped
                .as_chunks::<4>()
                .0
                .iter()
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect())
        });
        // SAFETY: made above on this device; the submission was waited for.
        unsafe { self.gpu.device.destroy_image_view(storage, None) };
        staging.destroy(&self.gpu);
        out
    }

    /// Uploads, prepares the background, enhances in place and reads back, in one submission.
    fn run_in_place(
        &self,
        image: &DeviceImage,
        storage: vk::ImageView,
        staging: &GpuBuffer,
        (region, format): ((u32, u32), PixelFormat),
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<(), GpuError> {
        let gpu = &self.gpu;
        let shape = ViewShape {
            format,
            width: region.0,
            pixels_in: PixelsIn::Image,
        };
        let (mut bg, mut view) = self.stage_shaped(camera, (shape, region.1))?;
        self.engine.bind_app_image(gpu, &view, storage);
        let mapping = params.camera_mapping();
        let place = [ImageRegion {
            image: image.raw,
            array_index: 0,
            offset: (0, 0),
            extent: region,
        }];
        let done = self.submit(|cmd| {
            use vk::PipelineStageFlags as S;
            // A new image, in the layout an app leaves its images in at xrEndFrame.
            let attachment = (
                S::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            );
            let layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
            record_first_layout(gpu, cmd, &[image.raw], layout, attachment);
            record_layout_barriers(gpu, cmd, &place, true);
            record_region_copy(gpu, cmd, &place[0], staging, false);
            barrier(gpu, cmd, S::TRANSFER, S::COMPUTE_SHADER);
            let rect = CameraRect::sampled_by(&[mapping], bg.size);
            self.engine
                .record_background(gpu, cmd, &bg, params, &rect)?;
            self.engine
                .record_enhance(gpu, cmd, &view, params, &mapping)?;
            barrier(gpu, cmd, S::COMPUTE_SHADER, S::TRANSFER);
            record_region_copy(gpu, cmd, &place[0], staging, true);
            Ok(())
        });
        self.engine.destroy_view(gpu, &mut view);
        bg.destroy(gpu);
        done
    }
}
