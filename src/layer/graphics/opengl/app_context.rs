//! The app's GL context as the layer reaches it, whichever window-system binding gave it: made
//! current on the calling thread around the layer's GL calls when it is not, and the GL entry
//! points for it.

use crate::gpu::opengl::{Gl, GlError};

/// What was current on the thread before the layer made the app's context current, to put
/// back (the binding's own kind).
pub type Previous = Box<dyn std::any::Any>;

pub trait AppContext {
    /// Makes the app's context current on this thread if it is not: Ok(None) when it already
    /// was, Ok(Some) with what to put back after, Err (a sentence) when it cannot be.
    fn enter(&self) -> Result<Option<Previous>, String>;
    /// Puts back what `enter` found current.
    fn leave(&self, previous: Option<Previous>);
    /// The GL entry points for the context (with it current).
    fn gl(&self) -> Result<Gl, GlError>;
    /// Which context this is: its display and context handles, as the binding gave them.
    fn key(&self) -> (usize, usize);
}

/// The app's context entered, left again when this is dropped: also when the layer's work in
/// it panics (the panic is caught at the layer's boundary, with the app's thread as it was).
pub struct Entered<'a> {
    context: &'a dyn AppContext,
    previous: Option<Option<Previous>>,
}

impl<'a> Entered<'a> {
    pub fn enter(context: &'a dyn AppContext) -> Result<Entered<'a>, String> {
        let previous = context.enter()?;
        Ok(Entered {
            context,
            previous: Some(previous),
        })
    }
}

impl Drop for Entered<'_> {
    fn drop(&mut self) {
        if let Some(previous) = self.previous.take() {
            self.context.leave(previous);
        }
    }
}

/// The message when the app's context cannot be made current here.
pub const NOT_CURRENT: &str = "the app's OpenGL context could not be made current on the thread calling the layer (is it current on another thread?)";
