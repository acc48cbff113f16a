//! What the engine keeps of a view region across frames: its buffers and pipelines' target,
//! and the image-copy path's image and write-back set.

use crate::gpu::vulkan::device::{GpuDevice, StorageImage};
use crate::gpu::vulkan::record::{Recorder, ViewTarget};
use ash::vk;

pub(super) struct PreparedView {
    pub(super) target: ViewTarget,
    pub(super) last_frame: u64,
    /// The image view bound as the view's `blurred_texels`.
    pub(super) texels: vk::ImageView,
    /// The image-copy path's image (`ViewPath::ImageCopy`): the region is copied into it,
    /// enhanced there (bound as the view's `app_image`, at its origin) and copied back.
    pub(super) own: Option<StorageImage>,
    /// The write-back's descriptor set (`ViewPath::ImageCopyTiles`), made at its first draw,
    /// with the pool it came from (which outlives the views).
    pub(super) write_back_set: Option<(vk::DescriptorPool, vk::DescriptorSet)>,
}

impl PreparedView {
    pub(super) fn destroy(&mut self, engine: &Recorder, gpu: &GpuDevice) {
        engine.destroy_view(gpu, &mut self.target);
        if let Some(mut own) = self.own.take() {
            own.destroy(gpu);
        }
        if let Some((pool, set)) = self.write_back_set.take() {
            // SAFETY: the set came from this pool (FREE_DESCRIPTOR_SET), which is still alive
            // (the write-back is destroyed after the views); the GPU is done with it.
            let _ = unsafe { gpu.device.free_descriptor_sets(pool, &[set]) };
        }
    }
}
