//! A frame's whole GPU work in one call (`FrameRunner::process`): the views' copies or in-place
//! images, the background (uploaded, or texels a source prepared), the passes, the overlays and
//! the captures, on the app's device and queue; and the pipelines' warm-up on CPU drivers, which
//! runs frames.

mod app_bindings;
mod app_views;
mod frame_record;
mod frame_runner;
mod frame_times;
mod frame_view;
mod overlay_copies;
mod prepared_background;
mod prepared_view;
mod tile_write_back;
mod warm_up;

pub(crate) use app_views::storage_view;
pub use app_views::{can_store, copy_path};
pub use frame_runner::{FrameOptions, FrameRunner, PipelinesReady};

pub use frame_view::{CapturedView, FrameView, ViewKey, ViewPath};
