//! A view of one array layer of an image of the app's (or the engine's), in a format the image
//! allows: what the sampled read samples and what the write-back draws into.

use super::error::{GpuError, VkResultExt};
use super::gpu_device::GpuDevice;
use ash::vk;

/// A 2D view of layer `layer` of `image`, in `vk_format` (the image's own, or one its
/// mutable format allows).
pub fn layer_view(
    gpu: &GpuDevice,
    image: vk::Image,
    layer: u32,
    vk_format: vk::Format,
) -> Result<vk::ImageView, GpuError> {
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .base_array_layer(layer)
        .layer_count(1);
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(vk_format)
        .subresource_range(range);
    // SAFETY: a valid create info for a live image of this device (the caller's contract).
    unsafe { gpu.device.create_image_view(&info, None) }.vk("vkCreateImageView")
}
