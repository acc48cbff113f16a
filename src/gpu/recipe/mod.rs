//! The method's recipe on one device: `Engine` holds the pipelines and the per-view and
//! background resources and records the passes (decode and blur of the background, classify,
//! finish_tiles, enhance) into a command buffer its caller owns.

mod camera_rect;
mod engine;
mod record;
mod resources;
mod shared_fetch;

pub use camera_rect::CameraRect;
pub use engine::Engine;
pub(crate) use resources::TEXELS_FORMAT;
pub use resources::{BackgroundFrame, Placement, ViewShape, ViewTarget};
pub use shared_fetch::shares_fetches;
