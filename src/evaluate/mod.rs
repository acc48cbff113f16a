//! Evaluation of an enhancement (docs/algorithm.md, Results): the paper's enhanced-pixel metric,
//! the perceptual model's perceived contrast, the simulated perceived image of an additive
//! display, and figures a person can look at. Pure CPU; it never runs the method itself.

pub mod animation;
pub mod class_figure;
pub mod figure;
pub mod font;
pub mod metric;
pub mod perceived;
pub mod perception_report;

pub use animation::{encode_apng, AnimationFrame};
pub use figure::{
    figure, figure_row, figure_with_app_images, figure_with_app_images_at, stack_rows,
};
pub use metric::{enhanced_mask, metrics, Metrics, Stats, JND_DELTA_E};
pub use perceived::perceived;
pub use perception_report::{perception_report, PerceptionReport};
