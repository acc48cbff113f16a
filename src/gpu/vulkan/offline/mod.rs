//! The engine on a device of its own, for the command line: whole images in and out, in place
//! or through copies, and the benchmark (`contrastxr bench`).

mod bench;
mod bench_case;
mod bench_rig;
mod image_copy_path;
mod in_place_region;
mod vk_offline;

pub use bench::BenchResult;
pub use bench_case::{camera_frame, content_pixel, BenchCase, Content, CAMERA_SIZE, WARM_UP_RUNS};
pub use image_copy_path::AppImage;
pub use vk_offline::VkOffline;
