//! The compute programs: built from the embedded GLSL in the order they are needed, through the
//! program binary cache on disk.

mod binary_cache;
mod programs;

pub use binary_cache::{BinaryCache, ProgramBinaries};
pub(in crate::gpu::opengl) use programs::{classify, enhance, enhance_ablated, GL_FINISH_TILES};
pub use programs::{gl_sources_id, Program, Programs};
