//! What the last app's log said of the GPU time the layer's work took per frame: the layer
//! logs it once a minute and when a session ends.

use super::app::LastApp;
use super::finding::Finding;
use contrastxr::layer::log::GPU_TIME;

pub fn finding(last: &LastApp) -> Finding {
    const NAME: &str = "gpu-time";
    match last.last_line(GPU_TIME) {
        Some(text) => Finding::ok(NAME, format!("last app: {text}")),
        None => Finding::ok(
            NAME,
            "the last app logged no GPU time of the layer's (it is logged after each minute of \
             enhanced frames and when a session ends; a queue without timestamps is not timed)",
        ),
    }
}
