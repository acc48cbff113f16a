//! Views of the app's image layers: storage views that views are enhanced in place in, and
//! sampled views that the sampled read reads (`ViewPath::SampledTiles`): made at a layer's
//! first such frame, kept while its swapchain lives (the images are the swapchain's),
//! destroyed with it or with the engine.

use super::frame_view::{FrameView, ViewPath};
use crate::gpu::core::PixelFormat;
use crate::gpu::vulkan::conv::VkFormat;
use crate::gpu::vulkan::device::{layer_view, GpuDevice, GpuError, VkResultExt};
use ash::vk;
use std::collections::HashMap;

/// (swapchain, image, array layer): one view of each kind each.
type Layer = (u64, vk::Image, u32);

#[derive(Default)]
pub struct AppImageViews {
    views: HashMap<Layer, vk::ImageView>,
    sampled: HashMap<Layer, vk::ImageView>,
}

impl AppImageViews {
    /// The storage view of `view`'s image layer, in the format its shaders declare.
    pub fn get(&mut self, gpu: &GpuDevice, view: &FrameView) -> Result<vk::ImageView, GpuError> {
        cached(&mut self.views, view, || {
            storage_view(gpu, view.image, view.key.array_index, view.format)
        })
    }

    /// The sampled view of `view`'s image layer, in the image's own format.
    pub fn get_sampled(
        &mut self,
        gpu: &GpuDevice,
        view: &FrameView,
    ) -> Result<vk::ImageView, GpuError> {
        // In the image's own format: the sampler decodes sRGB.
        cached(&mut self.sampled, view, || {
            layer_view(gpu, view.image, view.key.array_index, view.vk_format)
        })
    }

    /// Destroys the views of a swapchain's images. The GPU must be done with them.
    pub fn forget(&mut self, gpu: &GpuDevice, swapchain: u64) {
        for views in [&mut self.views, &mut self.sampled] {
            views.retain(|&(s, _, _), &mut v| {
                if s == swapchain {
                    // SAFETY: made by `get` on this device; the GPU no longer uses it.
                    unsafe { gpu.device.destroy_image_view(v, None) };
                }
                s != swapchain
            });
        }
    }

    /// Destroys every view. The GPU must be done with them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        for (_, v) in self.views.drain().chain(self.sampled.drain()) {
            // SAFETY: made by `get` on this device; the GPU no longer uses it.
            unsafe { gpu.device.destroy_image_view(v, None) };
        }
    }
}

/// `view`'s image layer's view in `views`, made by `make` the first time.
fn cached(
    views: &mut HashMap<Layer, vk::ImageView>,
    view: &FrameView,
    make: impl FnOnce() -> Result<vk::ImageView, GpuError>,
) -> Result<vk::ImageView, GpuError> {
    let layer = (view.key.swapchain, view.image, view.key.array_index);
    if let Some(&v) = views.get(&layer) {
        return Ok(v);
    }
    let v = make()?;
    views.insert(layer, v);
    Ok(v)
}

/// A storage view of layer `layer` of `image` (of `format`), in the format its in-place
/// shaders declare. The image must have storage usage (and, for sRGB, a mutable format).
pub fn storage_view(
    gpu: &GpuDevice,
    image: vk::Image,
    layer: u32,
    format: PixelFormat,
) -> Result<vk::ImageView, GpuError> {
    let view_format = format
        .in_place_view_format()
        .ok_or_else(|| GpuError::Unsupported(format!("{format:?} is not enhanced in place")))?;
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .base_array_layer(layer)
        .layer_count(1);
    // Only the storage usage: an sRGB image's UNORM view need not support the image's other
    // usages.
    let mut usage = vk::ImageViewUsageCreateInfo::default().usage(vk::ImageUsageFlags::STORAGE);
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(view_format)
        .subresource_range(range);
    let info = match format.srgb {
        true => info.push_next(&mut usage),
        false => info,
    };
    // SAFETY: a valid create info for a live image of this device (the caller's contract).
    unsafe { gpu.device.create_image_view(&info, None) }.vk("vkCreateImageView")
}

/// Whether `gpu` can store to images of `format` through its in-place storage view (and so
/// the layer asks the runtime for storage usage on its swapchains).
pub fn can_store(gpu: &GpuDevice, format: PixelFormat) -> bool {
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

/// The path of a view whose image the layer may not store to: through an image of the
/// engine's own (`ViewPath::ImageCopy`) where `gpu` can store to the format's
/// `image_copy_format`, else through a buffer.
pub fn copy_path(gpu: &GpuDevice, format: PixelFormat) -> ViewPath {
    let Some(own) = format.image_copy_format() else {
        return ViewPath::BufferCopy;
    };
    // SAFETY: physical belongs to this instance.
    let props = unsafe {
        gpu.instance
            .get_physical_device_format_properties(gpu.physical, own)
    };
    let needed = vk::FormatFeatureFlags::STORAGE_IMAGE;
    match props.optimal_tiling_features.contains(needed) {
        true => ViewPath::ImageCopy,
        false => ViewPath::BufferCopy,
    }
}
