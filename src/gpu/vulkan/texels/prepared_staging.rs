//! The host-visible buffers texels a background's source prepared are staged in, where the
//! views cannot sample them from mapped memory (gpu/vulkan/texels/texel_ring.rs), and for the offline engine
//! (`staging_buffer`).

use crate::gpu::core::blurred_texels::BlurredTexels;
use crate::gpu::vulkan::device::{GpuBuffer, GpuDevice, GpuError};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// A host-visible buffer the frame's commands copy from.
pub fn new_staging(gpu: &GpuDevice, bytes: u64) -> Result<GpuBuffer, GpuError> {
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    GpuBuffer::new(
        gpu,
        bytes,
        usage,
        MemoryLocation::CpuToGpu,
        "prepared texels",
    )
}

/// A host-visible buffer holding all of `texels`, laid out as the image (for `record_texels_upload`).
pub fn staging_buffer(gpu: &GpuDevice, texels: &BlurredTexels) -> Result<GpuBuffer, GpuError> {
    let mut buffer = new_staging(gpu, texels.bytes.len() as u64)?;
    buffer
        .write(&texels.bytes)
        .inspect_err(|_| buffer.destroy(gpu))?;
    Ok(buffer)
}
