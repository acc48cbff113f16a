//! Errors of the GPU engine. Every message is one sentence a user can act on.

use crate::gpu::core::shader_ids::NoShader;
use ash::vk;
use std::fmt;

#[derive(Debug)]
pub enum GpuError {
    /// The Vulkan loader (libvulkan.so.1) could not be loaded.
    NoLoader(String),
    /// No usable Vulkan device (none at all, or none with Vulkan 1.1 and a compute queue).
    NoDevice(String),
    /// A Vulkan call failed.
    Vulkan {
        call: &'static str,
        result: vk::Result,
    },
    /// gpu-allocator failed to allocate or free memory.
    Allocation(gpu_allocator::AllocationError),
    /// The request is outside what the engine supports (size, format, parameters).
    Unsupported(String),
    /// A pipeline the work needs is still being built on the engine's own thread.
    Pending,
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::NoLoader(e) => write!(
                f,
                "cannot load the Vulkan loader ({e}): install libvulkan1 and mesa-vulkan-drivers, or use --engine cpu"
            ),
            GpuError::NoDevice(e) => write!(
                f,
                "no usable Vulkan device ({e}): install mesa-vulkan-drivers (lavapipe) or a GPU driver, or use --engine cpu"
            ),
            GpuError::Vulkan { call, result } => write!(f, "{call} failed: {result}"),
            GpuError::Allocation(e) => write!(f, "GPU memory allocation failed: {e}"),
            GpuError::Unsupported(e) => write!(f, "{e}"),
            GpuError::Pending => write!(f, "the shader pipelines are still being built"),
        }
    }
}

impl std::error::Error for GpuError {}

impl From<NoShader> for GpuError {
    fn from(e: NoShader) -> Self {
        GpuError::Unsupported(e.to_string())
    }
}

impl From<gpu_allocator::AllocationError> for GpuError {
    fn from(e: gpu_allocator::AllocationError) -> Self {
        GpuError::Allocation(e)
    }
}

/// Names the failed call: `device.create_buffer(..).vk("vkCreateBuffer")?`.
pub trait VkResultExt<T> {
    fn vk(self, call: &'static str) -> Result<T, GpuError>;
}

impl<T> VkResultExt<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T, GpuError> {
        self.map_err(|result| GpuError::Vulkan { call, result })
    }
}
