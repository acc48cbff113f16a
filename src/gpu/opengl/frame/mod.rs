//! A frame's work on the app's context (`GlFrameRunner`): the views in place or through a buffer, the
//! passes, the overlays and captures, with the app's GL state saved and put back.

mod frame_runner;
mod frame_times;
mod frame_view;
mod prepared_background;
mod region;
pub mod state_guard;
mod variant_programs;
mod view_check;
mod view_pixels;
mod view_recipe;
mod warm_up;

pub use frame_runner::{GlFrameRunner, Outcome, StoreThrough};
pub use frame_view::{GlTarget, GlView};
pub(in crate::gpu::opengl) use region::{read_region, write_region};
