//! The method's recipe on one device: `Recorder` holds the pipelines and the per-view and
//! background resources and records the passes (decode and blur of the background, classify,
//! finish_tiles, enhance) into a command buffer its caller owns.

mod image_bindings;
mod passes;
mod recorder;
mod resources;
mod set_pool;
mod variant_pipelines;
mod write_back_draw;

pub use recorder::Recorder;
pub(crate) use resources::TEXELS_FORMAT;
pub use resources::{CameraResources, PixelsIn, Placement, ViewShape, ViewTarget};
pub use write_back_draw::{record_write_back, record_write_back_barrier, WriteBackDraw};
