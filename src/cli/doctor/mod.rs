//! `contrastxr doctor [--json]`: one screen saying whether the layer can work here, each finding
//! `ok`, `warn` or `problem` in one line, with a fix line when it is not ok. The checks: whether
//! the OpenXR loader finds the layer's manifest and can load the library it names, the active
//! runtime, the Vulkan devices, the config file, the background camera and the camera profile,
//! the device profile that matched the headset (and whether the camera it names is connected),
//! what the last app's log said about the layer (its session's graphics API among it) and the
//! GPU time its work took per frame, and
//! Steam's pressure-vessel setting; the report's header names the graphics APIs the layer
//! enhances. Exit status 1 when any finding is a problem (warnings alone leave it 0).

mod app;
mod camera;
mod finding;
mod gpu_time_finding;
mod library;
mod manifest;
mod profile;
mod render_nodes;
mod report;
mod runtime;
mod steam;

pub use report::{run, usage, OPTIONS};
