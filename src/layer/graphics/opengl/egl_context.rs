//! The app's EGL context (XR_MNDX_egl_enable) around the layer's GL calls: made current on the
//! calling thread without a surface when it is not (as the runtime does), what was current
//! put back after. EGL reports a context current on another thread as a failed call, no more.

use super::app_context::{AppContext, Previous as AnyPrevious, NOT_CURRENT};
use crate::gpu::opengl::{Gl, GlError};
use openxr_sys as xr;
use std::ffi::{c_void, CStr};

type GetProcAddress = xr::platform::EglGetProcAddressMNDX;
type GetCurrentContext = unsafe extern "C" fn() -> *mut c_void;
type GetCurrentDisplay = unsafe extern "C" fn() -> *mut c_void;
type GetCurrentSurface = unsafe extern "C" fn(i32) -> *mut c_void;
type MakeCurrent = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *mut c_void) -> u32;

const DRAW: i32 = 0x3059;
const READ: i32 = 0x305A;

struct Egl {
    get_current_context: GetCurrentContext,
    get_current_display: GetCurrentDisplay,
    get_current_surface: GetCurrentSurface,
    make_current: MakeCurrent,
}

/// The app's context from its EGL binding.
pub struct EglContext {
    get_proc_address: GetProcAddress,
    egl: Egl,
    display: *mut c_void,
    context: *mut c_void,
}

struct Previous {
    display: *mut c_void,
    draw: *mut c_void,
    read: *mut c_void,
    context: *mut c_void,
}

/// `name` through the binding's eglGetProcAddress (which EGL 1.5 answers for its own functions).
fn function(get: GetProcAddress, name: &CStr) -> Result<unsafe extern "system" fn(), String> {
    // SAFETY: the app's eglGetProcAddress with a NUL-terminated name.
    unsafe { get(name.as_ptr()) }.ok_or_else(|| {
        format!(
            "the app's eglGetProcAddress has no {}",
            name.to_string_lossy()
        )
    })
}

impl EglContext {
    /// The binding's context, or why its EGL cannot be used.
    pub fn new(b: &xr::GraphicsBindingEGLMNDX) -> Result<Self, String> {
        let get = b
            .get_proc_address
            .ok_or("the EGL binding has no getProcAddress")?;
        if b.display.is_null() || b.context.is_null() {
            return Err("the EGL binding has no display or context".into());
        }
        macro_rules! egl {
            ($name:literal, $ty:ty) => {{
                let f = function(get, $name)?;
                // SAFETY: the EGL function of that name has this C type.
                unsafe { std::mem::transmute::<unsafe extern "system" fn(), $ty>(f) }
            }};
        }
        Ok(EglContext {
            get_proc_address: get,
            egl: Egl {
                get_current_context: egl!(c"eglGetCurrentContext", GetCurrentContext),
                get_current_display: egl!(c"eglGetCurrentDisplay", GetCurrentDisplay),
                get_current_surface: egl!(c"eglGetCurrentSurface", GetCurrentSurface),
                make_current: egl!(c"eglMakeCurrent", MakeCurrent),
            },
            display: b.display,
            context: b.context,
        })
    }
}

impl AppContext for EglContext {
    fn enter(&self) -> Result<Option<AnyPrevious>, String> {
        let e = &self.egl;
        // SAFETY: EGL queries of this thread's current context, valid with none current.
        let current = unsafe { (e.get_current_context)() };
        let forced = crate::fault::hit("gl-make-current");
        if current == self.context && !forced {
            return Ok(None);
        }
        // SAFETY: as above.
        let previous = unsafe {
            Previous {
                display: (e.get_current_display)(),
                draw: (e.get_current_surface)(DRAW),
                read: (e.get_current_surface)(READ),
                context: current,
            }
        };
        let none = std::ptr::null_mut();
        // SAFETY: the binding's display and context, alive for the session; no surface.
        let made = unsafe { (e.make_current)(self.display, none, none, self.context) };
        // SAFETY: as above. The fault point fails after the switch.
        let now = unsafe { (e.get_current_context)() };
        if made == 0 || now != self.context || forced {
            // Whatever the failed switch left, this thread gets back what it had.
            self.leave(Some(Box::new(previous)));
            let injected = if forced {
                " (fault injected at gl-make-current)"
            } else {
                ""
            };
            return Err(format!("{NOT_CURRENT}{injected}"));
        }
        Ok(Some(Box::new(previous)))
    }

    fn leave(&self, previous: Option<AnyPrevious>) {
        let Some(p) = previous.and_then(|p| p.downcast::<Previous>().ok()) else {
            return;
        };
        let display = if p.display.is_null() {
            self.display
        } else {
            p.display
        };
        // SAFETY: what this thread had current a moment ago (or nothing).
        unsafe { (self.egl.make_current)(display, p.draw, p.read, p.context) };
    }

    fn key(&self) -> (usize, usize) {
        (self.display as usize, self.context as usize)
    }

    fn gl(&self) -> Result<Gl, GlError> {
        let get = self.get_proc_address;
        Gl::load(&mut |name| {
            // SAFETY: the app's eglGetProcAddress with a NUL-terminated name.
            unsafe { get(name.as_ptr()) }.map_or(std::ptr::null(), |f| f as *const c_void)
        })
    }
}
