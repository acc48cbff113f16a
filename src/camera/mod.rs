//! Background sources: the real world behind the display, as 8-bit sRGB RGBA frames.
//!
//! A [`Background`] is chosen by a spec string (`CONTRASTXR_BACKGROUND`, see [`parse_source`]):
//! a V4L2 camera, a PNG image, a video (numbered PNG frames or a Y4M file), a simulated camera
//! in a panorama world ([`world`]) or a flat colour.
//! Live sources run on their own thread and publish into a latest-frame mailbox; the render
//! thread only ever takes the newest frame and never waits for a camera or a file.
//!
//! This module must not know about the GPU engine or the OpenXR layer: it hands out
//! [`Frame`]s and a [`SourceStatus`]; what to do with them (preprocess once per new
//! `sequence`, pass through when `Lost`) is the consumer's business.
//! Privacy: a camera is open only while its [`Background`] lives, and no frame is written
//! anywhere except by `contrastxr camera test` when asked for an output folder.

mod background;
pub mod clock;
pub mod convert;
mod error;
mod files;
mod log_sink;
mod mailbox;
mod mjpeg;
mod pool;
pub(crate) mod priority;
pub mod rig;
mod smoothing;
pub mod source;
pub mod usb_id;
pub mod v4l2;
pub mod world;
mod y4m;

pub use background::Background;
pub use error::CameraError;
pub use log_sink::set_log_sink;
pub use mailbox::{Frame, SourceStatus};
pub use rig::{HeadPoses, WorldRig};
pub use source::{parse_source, CameraControls, CaptureConfig, SourceSpec, MAX_CAMERA_SIDE};
