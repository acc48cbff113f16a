//! The engine on a device of its own, for the command line: whole images in and out, in place
//! or through copies, and the benchmark (`contrastxr bench`).

mod bench;
mod bench_rig;
mod image_copy_path;
mod in_place_region;
mod vk_offline;

pub use image_copy_path::AppImage;
pub use vk_offline::VkOffline;
