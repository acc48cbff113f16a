//! The app's EGL context (XR_MNDX_egl_enable) around the layer's GL calls: made current on the
//! calling thread without a surface when it is not (as the runtime does), what was current
//! put back after. EGL reports a context current on another thread as a failed call, no more.
//!
//! eglGetCurrent* and eglMakeCurrent (when it releases) act on the thread's bound client API
//! (eglBindAPI), which is EGL_OPENGL_ES_API on a thread that never bound one, and an app may
//! bind another with its OpenGL context current. So the layer binds EGL_OPENGL_API for its
//! check and switch, and binds the app's API again when it leaves, on every path.

use super::app_context::{AppContext, Previous as AnyPrevious, NOT_CURRENT};
use crate::gpu::opengl::{Gl, GlError};
use openxr_sys as xr;
use std::ffi::{c_void, CStr};

type GetProcAddress = xr::platform::EglGetProcAddressMNDX;
type GetCurrentContext = unsafe extern "C" fn() -> *mut c_void;
type GetCurrentDisplay = unsafe extern "C" fn() -> *mut c_void;
type GetCurrentSurface = unsafe extern "C" fn(i32) -> *mut c_void;
type MakeCurrent = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *mut c_void) -> u32;
type QueryApi = unsafe extern "C" fn() -> u32;
type BindApi = unsafe extern "C" fn(u32) -> u32;
type GetError = unsafe extern "C" fn() -> i32;

const DRAW: i32 = 0x3059;
const READ: i32 = 0x305A;
/// The API of the app's context: desktop OpenGL (XR_KHR_opengl_enable; the engine refuses an
/// OpenGL ES context at its first frame).
const OPENGL_API: u32 = 0x30A2;
/// eglQueryAPI's answer on a thread of an EGL without OpenGL ES that never bound an API: it
/// cannot be bound again (eglBindAPI refuses it), so such a thread keeps EGL_OPENGL_API.
const NO_API: u32 = 0x3038;

struct Egl {
    get_current_context: GetCurrentContext,
    get_current_display: GetCurrentDisplay,
    get_current_surface: GetCurrentSurface,
    make_current: MakeCurrent,
    query_api: QueryApi,
    bind_api: BindApi,
    get_error: GetError,
}

/// The app's context from its EGL binding.
pub struct EglContext {
    get_proc_address: GetProcAddress,
    egl: Egl,
    display: *mut c_void,
    context: *mut c_void,
}

/// What `enter` changed on the thread, to undo in `leave`.
struct Previous {
    /// The client API the thread had bound, bound again last.
    api: u32,
    /// What was current for OpenGL before the switch to the app's context (None: it was
    /// current already, nothing switched).
    current: Option<Current>,
}

/// The thread's current OpenGL context and surfaces (with EGL_OPENGL_API bound).
struct Current {
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
                query_api: egl!(c"eglQueryAPI", QueryApi),
                bind_api: egl!(c"eglBindAPI", BindApi),
                get_error: egl!(c"eglGetError", GetError),
            },
            display: b.display,
            context: b.context,
        })
    }

    /// With EGL_OPENGL_API bound: the app's context made current if it is not, Ok(Some) with
    /// what was current; on failure what was current is put back.
    fn switch(&self) -> Result<Option<Current>, String> {
        let e = &self.egl;
        // SAFETY: EGL queries of this thread's current context, valid with none current.
        let current = unsafe { (e.get_current_context)() };
        let forced = crate::fault::hit("gl-make-current");
        if current == self.context && !forced {
            return Ok(None);
        }
        // SAFETY: as above.
        let previous = unsafe {
            Current {
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
            self.make_current(&previous);
            let injected = if forced {
                " (fault injected at gl-make-current)"
            } else {
                ""
            };
            return Err(format!("{NOT_CURRENT}{injected}"));
        }
        Ok(Some(previous))
    }

    /// Makes `c` current again (with EGL_OPENGL_API bound, as when it was found).
    fn make_current(&self, c: &Current) {
        let display = if c.display.is_null() {
            self.display
        } else {
            c.display
        };
        // SAFETY: what this thread had current a moment ago (or nothing).
        unsafe { (self.egl.make_current)(display, c.draw, c.read, c.context) };
    }

    /// Binds `api` on this thread, when it differs from EGL_OPENGL_API and can be bound.
    fn bind_api(&self, api: u32) {
        if api != OPENGL_API && api != NO_API {
            // SAFETY: an API this thread had bound, so one the implementation knows.
            unsafe { (self.egl.bind_api)(api) };
        }
    }
}

impl AppContext for EglContext {
    fn enter(&self) -> Result<Option<AnyPrevious>, String> {
        let e = &self.egl;
        // SAFETY: eglQueryAPI and eglBindAPI change only this thread's bound API.
        let api = unsafe { (e.query_api)() };
        if api != OPENGL_API {
            // SAFETY: as above; an EGL without desktop OpenGL refuses it and keeps the API,
            // but then the app's context cannot be OpenGL either.
            unsafe { (e.bind_api)(OPENGL_API) };
        }
        match self.switch() {
            Ok(None) if api == OPENGL_API => Ok(None),
            Ok(current) => Ok(Some(Box::new(Previous { api, current }))),
            Err(why) => {
                self.bind_api(api);
                // The failed switch's error is the layer's: the app's eglGetError does not
                // see it.
                // SAFETY: eglGetError reads and clears this thread's last EGL error.
                unsafe { (e.get_error)() };
                Err(why)
            }
        }
    }

    fn leave(&self, previous: Option<AnyPrevious>) {
        let Some(p) = previous.and_then(|p| p.downcast::<Previous>().ok()) else {
            return;
        };
        if let Some(current) = &p.current {
            self.make_current(current);
        }
        self.bind_api(p.api);
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

#[cfg(test)]
#[path = "egl_context_tests.rs"]
mod tests;
