//! Memory dependencies between the engine's passes and the copies around them.

use super::gpu_device::GpuDevice;
use ash::vk;

/// The memory accesses a set of stages can make (only those, or validation objects).
fn accesses(stages: vk::PipelineStageFlags) -> vk::AccessFlags {
    use vk::{AccessFlags as A, PipelineStageFlags as S};
    if stages.contains(S::ALL_COMMANDS) {
        return A::MEMORY_READ | A::MEMORY_WRITE;
    }
    let mut access = A::empty();
    if stages.contains(S::COMPUTE_SHADER) {
        access |= A::SHADER_READ | A::SHADER_WRITE;
    }
    if stages.contains(S::TRANSFER) {
        access |= A::TRANSFER_READ | A::TRANSFER_WRITE;
    }
    if stages.contains(S::HOST) {
        access |= A::HOST_READ | A::HOST_WRITE;
    }
    if stages.contains(S::DRAW_INDIRECT) {
        access |= A::INDIRECT_COMMAND_READ;
    }
    if stages.contains(S::COLOR_ATTACHMENT_OUTPUT) {
        access |= A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE;
    }
    access
}

/// A memory dependency between passes of this engine and the copies around them.
pub fn barrier(
    gpu: &GpuDevice,
    cmd: vk::CommandBuffer,
    src: vk::PipelineStageFlags,
    dst: vk::PipelineStageFlags,
) {
    let memory = [vk::MemoryBarrier::default()
        .src_access_mask(accesses(src))
        .dst_access_mask(accesses(dst))];
    // SAFETY: cmd is in the recording state (the caller's contract for every record_* call).
    unsafe {
        gpu.device.cmd_pipeline_barrier(
            cmd,
            src,
            dst,
            vk::DependencyFlags::empty(),
            &memory,
            &[],
            &[],
        )
    };
}

/// The layout change of an image of the engine's own (its one colour layer), after the
/// accesses `src_access` and before `dst_access`: one image memory barrier to record.
pub fn layout_change(
    image: vk::Image,
    (old, new): (vk::ImageLayout, vk::ImageLayout),
    (src_access, dst_access): (vk::AccessFlags, vk::AccessFlags),
) -> vk::ImageMemoryBarrier<'static> {
    vk::ImageMemoryBarrier::default()
        .old_layout(old)
        .new_layout(new)
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(colour_layer())
}

/// The one colour mip level and array layer of an image.
pub fn colour_layer() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1)
}
