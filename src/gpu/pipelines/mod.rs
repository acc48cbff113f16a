//! Building the compute pipelines: off the app's threads in the order they are needed, through
//! the pipeline cache on disk, warmed up on CPU drivers, and kept from racing the process's exit.

pub mod pipeline_cache;
mod pipeline_set;
mod process_exit;
mod warm_up;

pub use pipeline_cache::Origin;
pub(crate) use pipeline_set::binding_count;
pub use pipeline_set::{BuildMode, BuildReport, Pipelines, WarmUpHook};
pub(crate) use warm_up::{WarmUp, WarmUpSlot};
