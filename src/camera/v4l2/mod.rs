//! V4L2 cameras through the `v4l` crate: finding devices, listing their modes, choosing one,
//! and the capture thread.
//!
//! Device nodes are looked up in `/dev`, or in the folder named by `CONTRASTXR_V4L2_DIR`
//! (for unusual setups, and for the tests' stand-in device).

pub mod auto;
mod capture_thread;
mod choose;
pub mod controls;
mod devices;
mod listing;
pub mod usb;

pub use auto::looks_built_in;
pub(crate) use capture_thread::spawn;
pub use choose::{choose_mode, Mode};
pub use devices::*;
pub use listing::listing;
