//! Storage views of the app's image layers that views are enhanced in place in: made at a
//! layer's first in-place frame, kept while its swapchain lives (the images are the
//! swapchain's), destroyed with it or with the engine.

use super::device::GpuDevice;
use super::error::{GpuError, VkResultExt};
use super::frame_view::FrameView;
use ash::vk;
use std::collections::HashMap;

/// (swapchain, image, array layer): one storage view each.
type Layer = (u64, vk::Image, u32);

#[derive(Default)]
pub struct AppImageViews {
    views: HashMap<Layer, vk::ImageView>,
}

impl AppImageViews {
    /// The storage view of `view`'s image layer, in the format its shaders declare.
    pub fn get(&mut self, gpu: &GpuDevice, view: &FrameView) -> Result<vk::ImageView, GpuError> {
        let layer = (view.key.swapchain, view.image, view.key.array_index);
        if let Some(&v) = self.views.get(&layer) {
            return Ok(v);
        }
        let format = view.format.in_place_view_format().ok_or_else(|| {
            GpuError::Unsupported(format!("{:?} is not enhanced in place", view.vk_format))
        })?;
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .base_array_layer(view.key.array_index)
            .layer_count(1);
        // Only the storage usage: an sRGB image's UNORM view need not support the image's
        // other usages (its swapchain was made with the mutable-format usage).
        let mut usage = vk::ImageViewUsageCreateInfo::default().usage(vk::ImageUsageFlags::STORAGE);
        let info = vk::ImageViewCreateInfo::default()
            .image(view.image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range);
        let info = match view.format.srgb {
            true => info.push_next(&mut usage),
            false => info,
        };
        // SAFETY: the image is the app's swapchain image, alive while its swapchain is (the
        // caller forgets the swapchain's views before it is destroyed); a valid create info.
        let v = unsafe { gpu.device.create_image_view(&info, None) }.vk("vkCreateImageView")?;
        self.views.insert(layer, v);
        Ok(v)
    }

    /// Destroys the views of a swapchain's images. The GPU must be done with them.
    pub fn forget(&mut self, gpu: &GpuDevice, swapchain: u64) {
        self.views.retain(|&(s, _, _), &mut v| {
            if s == swapchain {
                // SAFETY: made by `get` on this device; the GPU no longer uses it.
                unsafe { gpu.device.destroy_image_view(v, None) };
            }
            s != swapchain
        });
    }

    /// Destroys every view. The GPU must be done with them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        for (_, v) in self.views.drain() {
            // SAFETY: made by `get` on this device; the GPU no longer uses it.
            unsafe { gpu.device.destroy_image_view(v, None) };
        }
    }
}

/// Whether `gpu` can store to images of `format` through its in-place storage view (and so
/// the layer asks the runtime for storage usage on its swapchains).
pub fn can_store(gpu: &GpuDevice, format: super::PixelFormat) -> bool {
    let Some(view) = format.in_place_view_format() else {
        return false;
    };
    // SAFETY: physical belongs to this instance.
    let props = unsafe {
        gpu.instance
            .get_physical_device_format_properties(gpu.physical, view)
    };
    props
        .optimal_tiling_features
        .contains(vk::FormatFeatureFlags::STORAGE_IMAGE)
}
