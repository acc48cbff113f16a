//! Building the compute pipelines: off the app's threads in the order they are needed, through
//! the pipeline cache on disk, and kept from racing the process's exit (the frame room warms
//! them up on CPU drivers).

pub mod pipeline_cache;
mod pipeline_set;
mod write_back;

pub use pipeline_cache::Origin;
pub(crate) use pipeline_set::binding_count;
pub use pipeline_set::{BuildMode, BuildReport, Pipelines, WarmUpHook};
pub use write_back::{
    write_back_modules, WriteBackAttachment, WriteBackConstants, WriteBackPass, WriteBackPipelines,
};
