//! The OpenGL bindings a session can come with: XR_KHR_opengl_enable's Xlib one and
//! XR_MNDX_egl_enable's EGL one, each made into the session's graphics on the app's context.

use super::egl_context::EglContext;
use super::gl_session::GlSession;
use super::glx_context::GlxContext;
use crate::layer::graphics::session_graphics::Bound;
use crate::layer::live_settings::Settings;
use openxr_sys as xr;

/// The session's graphics for an OpenGL Xlib binding (None: not one).
///
/// # Safety
/// `base` starts a structure of the type it names, from a chain the runtime accepted.
pub unsafe fn bind_xlib(base: &xr::BaseInStructure, settings: &Settings) -> Option<Bound> {
    if base.ty != xr::StructureType::GRAPHICS_BINDING_OPENGL_XLIB_KHR {
        return None;
    }
    // SAFETY: the type tag says this is an Xlib binding (the caller's contract).
    let b = unsafe { &*(base as *const _ as *const xr::GraphicsBindingOpenGLXlibKHR) };
    let context = GlxContext::new(b.x_display.cast(), b.glx_drawable, b.glx_context.cast());
    Some(match context {
        Ok(context) => {
            crate::layer::log::info(&format!(
                "session on the app's OpenGL (Xlib) context, background {}: enhancing (the context is checked at the first frame)",
                settings.background
            ));
            Bound::Enhanced(Box::new(GlSession::new("OpenGL (Xlib)", Box::new(context))))
        }
        Err(why) => Bound::PassThrough(format!("{why}: passing its frames through untouched")),
    })
}

/// The session's graphics for an EGL binding (XR_MNDX_egl_enable; None: not one).
///
/// # Safety
/// As for `bind_xlib`.
pub unsafe fn bind_egl(base: &xr::BaseInStructure, settings: &Settings) -> Option<Bound> {
    if base.ty != xr::StructureType::GRAPHICS_BINDING_EGL_MNDX {
        return None;
    }
    // SAFETY: the type tag says this is an EGL binding (the caller's contract).
    let b = unsafe { &*(base as *const _ as *const xr::GraphicsBindingEGLMNDX) };
    Some(match EglContext::new(b) {
        Ok(context) => {
            crate::layer::log::info(&format!(
                "session on the app's OpenGL (EGL) context, background {}: enhancing (the context is checked at the first frame)",
                settings.background
            ));
            Bound::Enhanced(Box::new(GlSession::new("OpenGL (EGL)", Box::new(context))))
        }
        Err(why) => Bound::PassThrough(format!("{why}: passing its frames through untouched")),
    })
}
