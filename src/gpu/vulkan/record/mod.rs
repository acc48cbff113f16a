//! The method's recipe on one device: `Engine` holds the pipelines and the per-view and
//! background resources and records the passes (decode and blur of the background, classify,
//! finish_tiles, enhance) into a command buffer its caller owns.

mod passes;
mod recorder;
mod resources;

pub use recorder::Engine;
pub(crate) use resources::TEXELS_FORMAT;
pub use resources::{BackgroundFrame, Placement, ViewShape, ViewTarget};
