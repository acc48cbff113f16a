//! A frame's views pointed at this frame's image of their swapchain (the swapchain's image
//! index changes each frame): the storage view in place, the sampled view for the sampled
//! read; from the views of `app_views.rs`.

use super::frame_runner::FrameRunner;
use super::frame_view::FrameView;
use crate::gpu::vulkan::device::GpuError;

impl FrameRunner {
    /// Points an in-place view at this frame's image of its swapchain (the GPU is idle).
    pub(super) fn bind_app_image(&mut self, item: &FrameView) -> Result<(), GpuError> {
        let image_view = self.app_views.get(&self.gpu, item)?;
        self.at_region(item);
        let target = &self.views[&item.key].target;
        self.engine.bind_app_image(&self.gpu, target, image_view);
        Ok(())
    }

    /// Points a view of the sampled read at this frame's image of its swapchain (the GPU is
    /// idle): the shaders read it at the region's place.
    pub(super) fn bind_app_texels(&mut self, item: &FrameView) -> Result<(), GpuError> {
        let image_view = self.app_views.get_sampled(&self.gpu, item)?;
        self.at_region(item);
        let target = &self.views[&item.key].target;
        self.engine.bind_app_texels(&self.gpu, target, image_view);
        Ok(())
    }

    /// Points `item`'s view's shaders at the region's place in the app's image.
    fn at_region(&mut self, item: &FrameView) {
        let target = &mut self.views.get_mut(&item.key).expect("ensured").target;
        // Inside the image: the layer checked the region against the swapchain's size.
        target.origin = (item.key.offset.0 as u32, item.key.offset.1 as u32);
    }
}
