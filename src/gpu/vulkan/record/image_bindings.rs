//! The image bindings of a view's descriptor set: the app's image layer (or the engine's own
//! image) the in-place shaders store to, the app's image layer the sampled read reads, and the
//! background texels the enhancement samples. Each in GENERAL while the passes run; the set
//! must not be in use.

use super::recorder::Recorder;
use super::resources::ViewTarget;
use crate::gpu::core::interface::{BINDING_APP_IMAGE, BINDING_APP_TEXELS, BINDING_BLURRED_TEXELS};
use crate::gpu::vulkan::device::GpuDevice;
use ash::vk;

impl Recorder {
    /// Binds the app's image layer a view in place is enhanced in (a storage view of it), or
    /// the engine's own image of the image-copy path.
    pub fn bind_app_image(&self, gpu: &GpuDevice, view: &ViewTarget, image_view: vk::ImageView) {
        let storage = vk::DescriptorType::STORAGE_IMAGE;
        write_image(gpu, view, (BINDING_APP_IMAGE, storage), image_view);
    }

    /// Binds the app's image layer the sampled read reads (ACCESS_SAMPLED): a view in the
    /// image's own format with sampled usage.
    pub fn bind_app_texels(&self, gpu: &GpuDevice, view: &ViewTarget, image_view: vk::ImageView) {
        let sampled = vk::DescriptorType::SAMPLED_IMAGE;
        write_image(gpu, view, (BINDING_APP_TEXELS, sampled), image_view);
    }

    /// Points a view's `blurred_texels` at `texels` (the background frame's image, or a mapped
    /// one of its size).
    pub fn bind_texels(&self, gpu: &GpuDevice, view: &ViewTarget, texels: vk::ImageView) {
        let sampled = vk::DescriptorType::SAMPLED_IMAGE;
        write_image(gpu, view, (BINDING_BLURRED_TEXELS, sampled), texels);
    }
}

/// Points binding `binding` of `view`'s set at `image_view`, in GENERAL.
fn write_image(
    gpu: &GpuDevice,
    view: &ViewTarget,
    (binding, ty): (u32, vk::DescriptorType),
    image_view: vk::ImageView,
) {
    let image = [vk::DescriptorImageInfo::default()
        .image_view(image_view)
        .image_layout(vk::ImageLayout::GENERAL)];
    let write = vk::WriteDescriptorSet::default()
        .dst_set(view.set)
        .dst_binding(binding)
        .descriptor_type(ty)
        .image_info(&image);
    // SAFETY: the set and the image view are valid; the caller guarantees the set is not in
    // use.
    unsafe { gpu.device.update_descriptor_sets(&[write], &[]) };
}
