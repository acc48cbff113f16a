//! A frame's work on the app's context (`GlFrameRunner`): the views in place or through a buffer, the
//! passes, the overlays and captures, with the app's GL state saved and put back.

mod gl_background;
mod gl_frame_runner;
mod gl_view;
mod program_warm_up;
mod region;
pub mod state_guard;
mod variant_programs;
mod view_check;
mod view_pixels;
mod view_recipe;

pub use gl_frame_runner::{GlFrameRunner, Outcome, StoreThrough};
pub use gl_view::{GlTarget, GlView};
pub(in crate::gpu::opengl) use region::{read_region, write_region};
