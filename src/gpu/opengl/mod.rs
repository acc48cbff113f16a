//! The GPU engine on the app's OpenGL context: the same compute passes as the Vulkan path,
//! from the same WGSL (build.rs writes GLSL 450 of the modules this backend runs, checked
//! against src/gpu/shaders/interface.rs as the SPIR-V is), in place through an image unit or
//! on a copy of each view in a buffer object.
//!
//! Called on the app's thread with its context current (the layer's xrEndFrame): no GL call is
//! made on a thread of the layer's own, the app's GL state is put back after each call
//! (state_guard.rs) and its pending GL error is never read or changed. Frames pass through untouched
//! while the programs build (programs.rs) and, with a one-sentence reason (gl_error.rs), where the
//! context, a format or a program cannot serve. Raw GL names and constants stay in this folder.

pub mod binary_cache;
pub mod caps;
pub mod functions;
mod gl_bench;
pub mod gl_engine;
pub mod gl_error;
pub mod gl_format;
pub mod gl_view;
pub mod offline;
mod program_warm_up;
pub mod programs;
mod region;
pub mod state_guard;
mod texel_buffers;
mod view_pixels;

pub use functions::Gl;
pub use gl_engine::{GlEngine, Outcome, StoreThrough};
pub use gl_error::GlError;
pub use gl_format::GlFormat;
pub use gl_view::{GlTarget, GlView};
pub use offline::GlOffline;
pub use programs::gl_sources_id;
