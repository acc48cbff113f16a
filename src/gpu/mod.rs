//! The GPU engine: background preparation and per-pixel enhancement from the SPIR-V and GLSL
//! built from `shaders/`, usable offline on a device of its own and inside an app on the app's
//! device or context. Knows nothing of OpenXR.
//!
//! Three parts: `core`, what no graphics API owns (the shader interface and ids, pixel formats
//! and their codec, camera rectangles, the texel slots a source fills, overlay runs, a frame's
//! inputs); and one folder per backend, `vulkan` and `opengl`, holding the same roles under the
//! same names: `device`, `pipelines` (OpenGL: programs), `record` (the passes), `frame` (a
//! frame's work inside an app), `texels` (the background's texels on the device), `offline`
//! (the command line's engine and benchmark) and `conv` (the API's names for core's types).

pub mod core;
pub mod opengl;
pub mod vulkan;

pub use self::core::{BackgroundInput, CameraRect, OfflineBackend, PixelFormat, PixelLayout};
pub use vulkan::device::{DeviceOptions, GpuDevice, GpuError};
pub use vulkan::frame::{CapturedView, FrameOptions, FrameRunner, FrameView, ViewKey, ViewPath};
pub use vulkan::offline::{compiled_shader_statistics, ShaderStatistics, VkOffline};
pub use vulkan::pipelines::StatisticValue;
pub use vulkan::record::{CameraResources, PixelsIn, Placement, Recorder, ViewShape, ViewTarget};
