//! Why a background source could not be opened.

use std::fmt;

/// Why a background source could not be opened.
#[derive(Debug)]
pub enum CameraError {
    /// No capture device at the path, or none at all for `v4l2:auto`.
    NoDevice(String),
    /// The device offers no pixel format this module can convert.
    Unsupported(String),
    /// An I/O or driver error while opening or negotiating.
    Device(String),
    /// An image or video file is missing or unreadable.
    File(String),
    /// The device exists but another program is capturing from it (EBUSY).
    Busy(String),
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CameraError::NoDevice(m)
            | CameraError::Unsupported(m)
            | CameraError::Device(m)
            | CameraError::File(m)
            | CameraError::Busy(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for CameraError {}
