//! Building the compute pipelines: off the app's threads in the order they are needed, through
//! the pipeline cache on disk, and kept from racing the process's exit (the frame room warms
//! them up on CPU drivers); and the image-copy path's write-back, a graphics pipeline per
//! attachment format that draws the listed tiles back into the app's image; and what the
//! driver's compiler says of a pipeline (its statistics, for the benchmark).

pub mod pipeline_cache;
mod pipeline_set;
mod shader_statistics;
mod write_back_attachment;
mod write_back_pipelines;

pub use pipeline_cache::Origin;
pub(crate) use pipeline_set::{binding_count, create_layouts};
pub use pipeline_set::{BuildMode, BuildReport, Pipelines, WarmUpHook};
pub use shader_statistics::{shader_statistics, ExecutableStatistics, StatisticValue};
pub use write_back_attachment::WriteBackAttachment;
pub use write_back_pipelines::{
    write_back_modules, WriteBackConstants, WriteBackPass, WriteBackPipelines,
};
