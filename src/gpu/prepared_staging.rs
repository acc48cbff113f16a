//! The host-visible buffers texels a background's source prepared are staged in, where the
//! views cannot sample them from mapped memory (gpu/texel_ring.rs), and for the offline engine
//! (gpu/prepared_background.rs).

use super::buffer::GpuBuffer;
use super::device::GpuDevice;
use super::error::GpuError;
use ash::vk;
use gpu_allocator::MemoryLocation;

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
