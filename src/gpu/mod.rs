//! The GPU engine (ash + gpu-allocator + the SPIR-V built from `shaders/`): background
//! preparation and per-pixel enhancement, usable offline on its own device and recorded into
//! someone else's command buffer inside an app. Knows nothing of OpenXR.
//!
//! Rooms by job, each with its own public surface: `device` (the device and its resources),
//! `shaders` (the shader interface), `pipelines` (building them), `recipe` (the passes on one
//! device), `frame` (a frame's work inside an app), `texels` (texels a source prepared),
//! `offline` (the command line's engine and benchmark); and `opengl`, the same passes on an
//! OpenGL app's context.

pub mod device;
pub mod frame;
pub mod offline;
pub mod opengl;
pub mod pipelines;
pub mod recipe;
pub mod shaders;
pub mod texels;

pub use device::{DeviceOptions, GpuDevice, GpuError, PixelFormat, PixelLayout};
pub use frame::{
    CapturedView, FrameBackground, FrameEngine, FrameOptions, FrameView, ViewKey, ViewPath,
};
pub use offline::OfflineEngine;
pub use recipe::{BackgroundFrame, CameraRect, Engine, Placement, ViewShape, ViewTarget};
