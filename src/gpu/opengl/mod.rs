//! The OpenGL backend: the same compute passes as the Vulkan backend, from the same WGSL
//! (build.rs writes GLSL 450 of the modules this backend runs, checked against
//! src/gpu/core/interface.rs as the SPIR-V is), on the app's context, in place through an image
//! unit or on a copy of each view in a buffer object. The same roles as `vulkan/`: `device` (the
//! functions, the context's capabilities, errors), `pipelines` (the programs, their binary cache
//! and background builds), `record` (a view's steps as GL calls), `frame` (a frame's work:
//! `GlFrameRunner`, the app's state kept), `texels`,
//! `offline` (a context of its own for the command line and the benchmark) and `conv`.
//!
//! Called on the app's thread with its context current (the layer's xrEndFrame): no GL call is
//! made on a thread of the layer's own but in a context of its own, the app's GL state is put
//! back after each call (frame/state_guard.rs) and its pending GL error is never read or
//! changed. Frames pass through untouched while the programs build (pipelines/programs.rs) and,
//! with a one-sentence reason (device/error.rs), where the context, a format or a program cannot
//! serve. Raw GL names and constants stay in this folder.

pub mod conv;
pub mod device;
pub mod frame;
pub mod offline;
pub mod pipelines;
mod record;
mod texels;

pub use conv::GlFormat;
pub use device::{Gl, GlError};
pub use frame::{GlFrameRunner, GlTarget, GlView, Outcome, StoreThrough};
pub use offline::GlOffline;
pub use pipelines::{gl_sources_id, BinaryCache, ProgramBinaries};
