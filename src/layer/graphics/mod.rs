//! The seam between the layer and the app's graphics API. One folder per API owns what only
//! that API knows: its graphics binding (read at xrCreateSession), its swapchain images (what
//! xrEnumerateSwapchainImages gives), the pixel format of a swapchain's format, and how a
//! view's region of an image is enhanced. The rest of the layer (sessions, swapchains, the
//! frame's views and their camera mappings, the background, the indicator, captures) speaks
//! only [`SessionGraphics`]. The method's recipe (passes, parameters, shader interface) is
//! shared below this seam, in `gpu/`.
//!
//! A new API is a new folder here with a `bind` function, listed in `bindings::BINDINGS`.

pub mod bindings;
#[cfg(test)]
pub mod fake_graphics;
pub mod opengl;
pub mod session_graphics;
pub mod vulkan;

pub use bindings::{bind, forget_instance, instance_created, intercepted, ENHANCED_APIS};
pub use session_graphics::{Bound, CapturedImage, NotDone, SessionGraphics, ViewImage};
