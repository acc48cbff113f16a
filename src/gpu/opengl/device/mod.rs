//! The OpenGL functions the backend loads from the app's context, what that context can do, and
//! the backend's errors.

pub mod caps;
mod error;
pub mod functions;

pub use error::GlError;
pub use functions::Gl;
