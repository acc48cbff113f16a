//! The app's image layer that the image-copy path's write-back draws into: a view of it in
//! its own format and a framebuffer of the write-back's render pass
//! (src/gpu/vulkan/pipelines/write_back_pipelines.rs).

use crate::gpu::vulkan::device::{layer_view, GpuDevice, GpuError, VkResultExt};
use ash::vk;

/// The app's image layer as the write-back's attachment: a view in its own format and a
/// framebuffer reaching the region's far corner.
pub struct WriteBackAttachment {
    view: vk::ImageView,
    framebuffer: vk::Framebuffer,
}

impl WriteBackAttachment {
    pub fn framebuffer(&self) -> vk::Framebuffer {
        self.framebuffer
    }

    pub fn new(
        gpu: &GpuDevice,
        render_pass: vk::RenderPass,
        (image, vk_format, layer): (vk::Image, vk::Format, u32),
        size: (u32, u32),
    ) -> Result<Self, GpuError> {
        let d = &gpu.device;
        let view = layer_view(gpu, image, layer, vk_format)?;
        let views = [view];
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(render_pass)
            .attachments(&views)
            .width(size.0)
            .height(size.1)
            .layers(1);
        // SAFETY: the view and render pass are valid and agree in format.
        match unsafe { d.create_framebuffer(&info, None) }.vk("vkCreateFramebuffer") {
            Ok(framebuffer) => Ok(WriteBackAttachment { view, framebuffer }),
            Err(e) => {
                // SAFETY: our own view, used by nothing.
                unsafe { d.destroy_image_view(view, None) };
                Err(e)
            }
        }
    }

    /// Destroys the framebuffer and view. The GPU must be done with them.
    pub fn destroy(&mut self, gpu: &GpuDevice) {
        // SAFETY: our own objects, no longer in use (the caller's contract).
        unsafe {
            gpu.device.destroy_framebuffer(self.framebuffer, None);
            gpu.device.destroy_image_view(self.view, None);
        }
    }
}
