//! The engine on a device of its own, for the command line: whole images in and out, in place
//! or through copies, and the benchmark (`contrastxr bench`).

mod bench;
mod bench_rig;
mod bench_shaders;
mod image_copy_path;
mod in_place_region;
mod offline_engine;

pub use bench_shaders::{compiled_shader_statistics, ShaderStatistics};
pub use image_copy_path::AppImage;
pub use offline_engine::VkOffline;
