//! What the frame engine remembers of a frame whose texels its background's source prepared
//! (gpu/prepared_background.rs), and the host-visible buffers such texels are staged in where
//! the views cannot sample them from mapped memory (gpu/texel_ring.rs).

use super::buffer::GpuBuffer;
use super::device::GpuDevice;
use super::error::GpuError;
use ash::vk;
use gpu_allocator::MemoryLocation;

#[derive(Default)]
pub struct PreparedStaging {
    /// The camera buffer does not hold the frame in use (its texels came prepared).
    pub(super) camera_behind: bool,
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
