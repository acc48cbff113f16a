//! OpenGL sessions (XR_KHR_opengl_enable with the Xlib binding, XR_MNDX_egl_enable): the GL
//! engine on the app's own context, made current around the layer's calls when it is not
//! (glx_context.rs, egl_context.rs), the app's swapchain images as GL texture names. No GL call happens on a thread of the layer's own.

mod app_context;
mod build_settle;
mod build_watch;
mod egl_context;
mod gl_bindings;
mod gl_frame_call;
mod gl_session;
mod glx_context;
mod left_engines;
mod program_builder;

pub use gl_bindings::{bind_egl, bind_xlib};
