//! The GPU engine (ash + gpu-allocator + the SPIR-V built from `shaders/`): background
//! preparation and per-pixel enhancement, usable offline on its own device and recorded into
//! someone else's command buffer inside an app. Knows nothing of OpenXR.

pub mod app_image;
pub mod app_views;
// The shader's approximations mirrored in f32: only their accuracy tests use them.
#[cfg(test)]
mod approx;
pub mod barrier;
pub mod bench;
mod bench_case;
mod bench_rig;
pub mod buffer;
pub mod camera_rect;
pub mod codes;
pub mod commands;
pub mod device;
pub mod engine;
pub mod error;
pub mod format;
pub mod frame;
mod frame_record;
pub mod frame_view;
pub mod image_copy;
pub mod interface;
pub mod offline;
mod offline_in_place;
pub mod overlay;
mod pinned_libraries;
pub mod pipeline_cache;
pub mod pipelines;
pub mod pixel_codec;
pub mod prepared_background;
pub mod prepared_staging;
pub mod process_exit;
pub mod push_constants;
mod record;
pub mod resources;
pub mod shader_ids;
pub mod shaders;
pub mod shared_fetch;
mod storage_image;
pub mod texel_ring;
pub mod texel_slots;
pub mod warm_up;

pub use device::{DeviceOptions, GpuDevice};
pub use engine::{BackgroundFrame, CameraRect, Engine, Placement, ViewShape, ViewTarget};
pub use error::GpuError;
pub use format::{PixelFormat, PixelLayout};
pub use frame::{FrameBackground, FrameEngine, FrameOptions};
pub use frame_view::{CapturedView, FrameView, ViewKey};
pub use offline::OfflineEngine;
