//! The Vulkan backend (ash + gpu-allocator + the SPIR-V build.rs compiles), by role: `device`
//! (the instance and device, its own or the app's, and its resources), `pipelines` (building
//! them off the app's threads, their cache), `record` (the method's passes recorded into a
//! caller's command buffer), `frame` (a frame's whole work inside an app), `texels` (prepared
//! texels on the device), `offline` (the command line's engine and benchmark) and `conv`
//! (Vulkan's names for core's types).

pub mod conv;
pub mod device;
pub mod frame;
pub mod offline;
pub mod pipelines;
pub mod record;
mod texels;

pub use conv::VkFormat;
