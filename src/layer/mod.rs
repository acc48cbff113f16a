//! The OpenXR API layer `XR_APILAYER_CONTRASTXR_color_contrast`: loader negotiation, dispatch,
//! sessions and swapchains, and the enhancement of every projection view at xrEndFrame.
//! It must never crash or corrupt the host app: every entry point catches panics, and any
//! failure turns the affected session into pass-through with one log line.

mod app_spaces;
mod blend;
pub mod capture_files;
mod capture_report;
mod capture_writer;
mod dispatch;
mod elevated;
mod end_frame;
mod entry;
#[cfg(test)]
mod fake_runtime;
mod ffi;
mod frame_retry;
mod gpu_time;
pub mod graphics;
mod headset_settings;
mod image_states;
pub mod indicator;
pub mod installed_files;
pub mod live_settings;
pub mod log;
pub mod log_file;
mod motion;
mod reach_advice;
pub mod session;
mod session_motion;
mod sources;
mod spaces;
mod state;
mod swapchain;
mod swapchain_plan;
mod timespec;
mod view_mappings;

pub use entry::{xrNegotiateLoaderApiLayerInterface, LAYER_NAME};
