//! Where the frame engine keeps texels its background's source prepared, between writing them
//! and recording their copy (gpu/prepared_background.rs).

use super::buffer::GpuBuffer;
use super::device::GpuDevice;
use super::engine::CameraRect;
use super::error::GpuError;
use ash::vk;
use gpu_allocator::MemoryLocation;

/// The frame engine's staging buffer for prepared texels.
#[derive(Default)]
pub struct PreparedStaging {
    pub(super) buffer: Option<GpuBuffer>,
    /// The rectangle written into `buffer` and not yet copied into the image.
    pub(super) pending: Option<CameraRect>,
    /// The camera buffer does not hold the frame in use (its texels came prepared).
    pub(super) camera_behind: bool,
}

impl PreparedStaging {
    pub(super) fn destroy(&mut self, gpu: &GpuDevice) {
        if let Some(mut b) = self.buffer.take() {
            b.destroy(gpu);
        }
    }
}

/// A host-visible buffer the frame's commands copy from.
pub(super) fn new_staging(gpu: &GpuDevice, bytes: u64) -> Result<GpuBuffer, GpuError> {
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    GpuBuffer::new(
        gpu,
        bytes,
        usage,
        MemoryLocation::CpuToGpu,
        "prepared texels",
    )
}
