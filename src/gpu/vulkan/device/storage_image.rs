//! A storage image of the engine's own with its view: what the warm-up binds where an
//! in-place shader expects the app's image (gpu/vulkan/frame/warm_up.rs), and what the image-copy
//! path copies a view's region into and enhances there (gpu/frame/, gpu/offline/).

use super::device_image::DeviceImage;
use super::error::{GpuError, VkResultExt};
use super::gpu_device::GpuDevice;
use ash::vk;

pub struct StorageImage {
    pub image: DeviceImage,
    pub view: vk::ImageView,
    pub format: vk::Format,
}

impl StorageImage {
    /// A `size` image of `format` with storage usage (UNDEFINED layout) and its view.
    pub fn new(gpu: &GpuDevice, size: (u32, u32), format: vk::Format) -> Result<Self, GpuError> {
        Self::with_usage(gpu, size, format, vk::ImageUsageFlags::STORAGE)
    }

    /// A `size` image of `format` that regions of an app's image are copied into and back
    /// (the image-copy path): storage and transfer usage (UNDEFINED layout), and its view.
    pub fn for_copies(
        gpu: &GpuDevice,
        size: (u32, u32),
        format: vk::Format,
    ) -> Result<Self, GpuError> {
        use vk::ImageUsageFlags as U;
        Self::with_usage(
            gpu,
            size,
            format,
            U::STORAGE | U::TRANSFER_SRC | U::TRANSFER_DST,
        )
    }

    fn with_usage(
        gpu: &GpuDevice,
        size: (u32, u32),
        format: vk::Format,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self, GpuError> {
        let mut image = DeviceImage::with_usage(gpu, size, format, usage)?;
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        let info = vk::ImageViewCreateInfo::default()
            .image(image.raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range);
        // SAFETY: a view of our own image, in its format.
        match unsafe { gpu.device.create_image_view(&info, None) }.vk("vkCreateImageView") {
            Ok(view) => Ok(StorageImage {
                image,
                view,
                format,
            }),
            Err(e) => {
                image.destroy(gpu);
                Err(e)
            }
        }
    }

    /// Destroys the view and the image. The GPU must be done with them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: our own view; the GPU no longer uses it (the caller's contract).
        unsafe { gpu.device.destroy_image_view(self.view, None) };
        self.image.destroy(gpu);
    }
}
