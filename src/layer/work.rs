//! The unit of the layer's GPU work: one view region of a swapchain image, and the key the
//! processor keeps that region's buffers under.

use crate::algorithm::mapping::CameraMapping;
use crate::gpu::image_copy::ImageRegion;
use crate::gpu::PixelFormat;
use ash::vk;

/// One region of a swapchain image to enhance.
#[derive(Clone, Debug)]
pub struct WorkItem {
    pub key: ViewKey,
    pub image: vk::Image,
    pub format: PixelFormat,
    pub vk_format: vk::Format,
    /// Where this view's display pixels lie in the camera image.
    pub mapping: CameraMapping,
}

impl WorkItem {
    pub fn region(&self) -> ImageRegion {
        ImageRegion {
            image: self.image,
            array_index: self.key.array_index,
            offset: self.key.offset,
            extent: self.key.extent,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ViewKey {
    pub swapchain: u64,
    pub offset: (i32, i32),
    pub extent: (u32, u32),
    pub array_index: u32,
}
