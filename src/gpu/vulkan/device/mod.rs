//! The device and its resources: the Vulkan instance and device (its own, or the app's), the
//! buffers and images the engine allocates, command buffers, barriers and image copies. The only
//! room whose public types hold raw Vulkan handles in public fields.

pub mod app_queue;
mod barrier;
mod buffer;
mod commands;
mod compute_device;
mod device_image;
mod error;
mod gpu_device;
mod gpu_timer;
mod image_copy;
mod layer_view;
mod physical_devices;
mod pinned_libraries;
mod storage_image;

pub use barrier::{barrier, colour_layer, layout_change};
pub use buffer::{record_buffer_copy, GpuBuffer};
pub use commands::Commands;
pub use device_image::DeviceImage;
pub use error::{GpuError, VkResultExt};
pub use gpu_device::{DeviceKind, DeviceOptions, GpuDevice};
pub use gpu_timer::GpuTimer;
pub use image_copy::{
    record_first_layout, record_image_region_copy, record_layout_barriers, record_region_copy,
    ImageRegion,
};
pub use layer_view::layer_view;
pub use physical_devices::{physical_devices, PhysicalDeviceInfo};
pub(crate) use storage_image::StorageImage;
