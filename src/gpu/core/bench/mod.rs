//! The benchmark's cases and results, the same for every backend (`contrastxr bench`): what is
//! timed (sizes, views, content, the camera frame) and the figures a backend reports.

mod bench_case;
mod bench_result;

pub use bench_case::{
    camera_frame, content_pixel, Ablation, BenchCase, Content, CAMERA_SIZE, WARM_UP_RUNS,
};
pub use bench_result::{median, BenchResult};
