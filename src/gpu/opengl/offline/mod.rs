//! The backend on a context of its own (EGL, surfaceless): whole images for the command line and
//! the layer's program builder, and the benchmark (`contrastxr bench --engine opengl`).

mod bench;
mod offline_engine;

pub use offline_engine::GlOffline;
