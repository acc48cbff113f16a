//! Which window-system binding an OpenGL session's context comes through.

/// How an OpenGL session gets the app's context.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlBinding {
    /// XrGraphicsBindingOpenGLXlibKHR on a GLX context.
    Xlib,
    /// XrGraphicsBindingEGLMNDX on an EGL context.
    Egl,
}

impl GlBinding {
    pub fn name(self) -> &'static str {
        match self {
            GlBinding::Xlib => "xlib",
            GlBinding::Egl => "egl",
        }
    }
}
