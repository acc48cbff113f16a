//! Why the OpenGL backend leaves a frame untouched: each a sentence, which the layer logs once
//! as the reason its views pass through.

use std::fmt;

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GlError {
    /// The loader has no address for a GL function.
    MissingFunction(&'static str),
    /// The context cannot run the backend (version, profile, extensions).
    Unsupported(String),
    /// A texture's internal format the backend does not enhance.
    Format(u32),
    /// A program failed to compile or link (the driver's log, first line).
    Program { name: String, log: String },
    /// The context was lost (the fault point: the layer never queries the reset status).
    ContextLost,
    /// A binding of the app's the call would change could not be put back (the reason): this
    /// frame passes through untouched.
    Unrestorable(&'static str),
    /// The driver did not make a buffer or texture (out of memory).
    Allocation(&'static str),
    /// The offline context could not be made (EGL).
    Context(String),
    /// A view or background the call cannot take (sizes, data length).
    Input(String),
}

impl fmt::Display for GlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GlError::MissingFunction(name) => {
                write!(f, "the OpenGL library has no {name}, so OpenGL frames pass through")
            }
            GlError::Unsupported(why) => write!(f, "{why}, so OpenGL frames pass through"),
            GlError::Format(format) => write!(
                f,
                "the swapchain's OpenGL format {format:#06x} is not one the layer enhances (GL_RGBA8, GL_SRGB8_ALPHA8, GL_RGBA16, GL_RGBA16F, GL_RGB10_A2), so its views pass through"
            ),
            GlError::Program { name, log } => write!(
                f,
                "the OpenGL program {name} did not build ({log}), so OpenGL frames pass through"
            ),
            GlError::ContextLost => {
                write!(f, "the app's OpenGL context was lost, so its frames pass through")
            }
            GlError::Allocation(what) => write!(
                f,
                "the OpenGL driver could not make the layer's {what} (out of memory?), so the frame passes through"
            ),
            GlError::Unrestorable(why) => write!(
                f,
                "{why}, which the layer could not bind back after its work, so frames pass through untouched while it is so"
            ),
            GlError::Context(why) => write!(f, "no offline OpenGL context: {why}"),
            GlError::Input(why) => write!(f, "{why}"),
        }
    }
}

impl std::error::Error for GlError {}
