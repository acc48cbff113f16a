//! The OpenXR API layer `XR_APILAYER_CONTRASTXR_color_contrast`: loader negotiation, dispatch,
//! sessions and swapchains, and the enhancement of every projection view at xrEndFrame.
//! It must never crash or corrupt the host app: every entry point catches panics, and any
//! failure turns the affected session into pass-through with one log line.

mod app_spaces;
mod app_vulkan;
mod blend;
pub mod capture;
mod device;
mod dispatch;
mod entry;
mod ffi;
mod frame;
mod image_states;
mod in_place;
pub mod indicator;
pub mod install;
pub mod log;
mod motion;
mod processor;
mod registration;
pub mod session;
mod session_motion;
pub mod settings;
mod sources;
mod spaces;
mod state;
mod swapchain;
mod timespec;

pub use entry::{xrNegotiateLoaderApiLayerInterface, LAYER_NAME};
