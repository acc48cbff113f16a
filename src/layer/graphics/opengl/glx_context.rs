//! The app's GLX context around the layer's GL calls, as the runtime does around its own: made
//! current on the calling thread when it is not, and what was current put back after. A
//! context current on another thread cannot be made current here: GLX raises an X error for
//! it, which Xlib's default handler turns into the app's exit, so a handler that only records
//! the error is in place around the call.

use super::app_context::{AppContext, Previous as AnyPrevious, NOT_CURRENT};
use crate::gpu::opengl::{Gl, GlError};
use std::ffi::{c_int, c_void, CStr};

type Display = c_void;
type GetCurrentContext = unsafe extern "C" fn() -> *mut c_void;
type GetCurrentDrawable = unsafe extern "C" fn() -> u64;
type GetCurrentDisplay = unsafe extern "C" fn() -> *mut Display;
type MakeContextCurrent = unsafe extern "C" fn(*mut Display, u64, u64, *mut c_void) -> c_int;
type ErrorHandler = Option<unsafe extern "C" fn(*mut Display, *mut c_void) -> c_int>;
type SetErrorHandler = unsafe extern "C" fn(ErrorHandler) -> ErrorHandler;
type Sync = unsafe extern "C" fn(*mut Display, c_int) -> c_int;

/// libGLX's and libX11's entry points, from the libraries the app already loaded.
struct Glx {
    get_current_context: GetCurrentContext,
    get_current_drawable: GetCurrentDrawable,
    get_current_read_drawable: GetCurrentDrawable,
    get_current_display: GetCurrentDisplay,
    make_context_current: MakeContextCurrent,
    set_error_handler: SetErrorHandler,
    sync: Sync,
}

/// A symbol of the process (global scope) or of one of `libraries` if already loaded.
fn symbol(name: &CStr, libraries: &[&CStr]) -> Option<*mut c_void> {
    // SAFETY: dlsym with RTLD_DEFAULT and a NUL-terminated name only looks a symbol up.
    let p = unsafe { libc::dlsym(libc::RTLD_DEFAULT, name.as_ptr()) };
    if !p.is_null() {
        return Some(p);
    }
    libraries.iter().find_map(|lib| {
        // SAFETY: RTLD_NOLOAD never loads a library; the reference taken is kept (the app's
        // libraries stay for the process).
        let h = unsafe { libc::dlopen(lib.as_ptr(), libc::RTLD_NOW | libc::RTLD_NOLOAD) };
        // SAFETY: a handle dlopen gave and a NUL-terminated name.
        let p = (!h.is_null()).then(|| unsafe { libc::dlsym(h, name.as_ptr()) })?;
        (!p.is_null()).then_some(p)
    })
}

impl Glx {
    fn load() -> Result<Glx, String> {
        const GL: [&CStr; 2] = [c"libGLX.so.0", c"libGL.so.1"];
        const X11: [&CStr; 1] = [c"libX11.so.6"];
        let find = |name: &'static CStr, libs: &[&CStr]| {
            symbol(name, libs)
                .ok_or_else(|| format!("no {} in the app's process", name.to_string_lossy()))
        };
        macro_rules! function {
            ($name:literal, $libs:expr, $ty:ty) => {{
                let p = find($name, &$libs)?;
                // SAFETY: the GLX or Xlib function of that name has this C type.
                unsafe { std::mem::transmute::<*mut c_void, $ty>(p) }
            }};
        }
        Ok(Glx {
            get_current_context: function!(c"glXGetCurrentContext", GL, GetCurrentContext),
            get_current_drawable: function!(c"glXGetCurrentDrawable", GL, GetCurrentDrawable),
            get_current_read_drawable: function!(
                c"glXGetCurrentReadDrawable",
                GL,
                GetCurrentDrawable
            ),
            get_current_display: function!(c"glXGetCurrentDisplay", GL, GetCurrentDisplay),
            make_context_current: function!(c"glXMakeContextCurrent", GL, MakeContextCurrent),
            set_error_handler: function!(c"XSetErrorHandler", X11, SetErrorHandler),
            sync: function!(c"XSync", X11, Sync),
        })
    }
}

/// The app's context from its Xlib binding.
pub struct GlxContext {
    glx: Glx,
    display: *mut Display,
    drawable: u64,
    context: *mut c_void,
}

/// What was current on the thread before the layer made the app's context current.
struct Previous {
    display: *mut Display,
    draw: u64,
    read: u64,
    context: *mut c_void,
}

/// The handler while the layer's make-current call runs: an X error of that call (a bad
/// drawable) would otherwise reach the app's handler, whose default ends the process. Whether
/// the call worked is read from GLX afterwards.
unsafe extern "C" fn ignore_x_error(_: *mut Display, _: *mut c_void) -> c_int {
    0
}

impl GlxContext {
    /// The binding's context, or why the process's GLX cannot be used.
    pub fn new(display: *mut Display, drawable: u64, context: *mut c_void) -> Result<Self, String> {
        if display.is_null() || context.is_null() {
            return Err("the OpenGL (Xlib) binding has no display or context".into());
        }
        Ok(GlxContext {
            glx: Glx::load()?,
            display,
            drawable,
            context,
        })
    }
}

impl AppContext for GlxContext {
    fn enter(&self) -> Result<Option<AnyPrevious>, String> {
        let g = &self.glx;
        // SAFETY: GLX queries of this thread's current context, valid with none current.
        let current = unsafe { (g.get_current_context)() };
        let forced = crate::fault::hit("gl-make-current");
        if current == self.context && !forced {
            return Ok(None);
        }
        // SAFETY: as above.
        let previous = unsafe {
            Previous {
                display: (g.get_current_display)(),
                draw: (g.get_current_drawable)(),
                read: (g.get_current_read_drawable)(),
                context: current,
            }
        };
        // SAFETY: the binding's display, drawable and context, which the app keeps alive for
        // the session. XSync first delivers the app's own pending errors to its own handler;
        // the app's handler is put back at once, after XSync has delivered any error of the
        // call.
        let made = unsafe {
            (g.sync)(self.display, 0);
            let app_handler = (g.set_error_handler)(Some(ignore_x_error));
            let made =
                (g.make_context_current)(self.display, self.drawable, self.drawable, self.context);
            (g.sync)(self.display, 0);
            (g.set_error_handler)(app_handler);
            made
        };
        // Whether this thread now has the app's context is what counts (not whether an X error
        // came meanwhile: it may be another thread's). The fault point fails after the switch.
        // SAFETY: as above.
        let now = unsafe { (g.get_current_context)() };
        if made == 0 || now != self.context || forced {
            // Whatever the failed switch left (Mesa unbinds the old context before a bind that
            // fails), this thread gets back what it had.
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

    fn key(&self) -> (usize, usize) {
        (self.display as usize, self.context as usize)
    }

    fn gl(&self) -> Result<Gl, GlError> {
        Self::load_gl()
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
        // SAFETY: what this thread had current a moment ago (or nothing), on its own display.
        unsafe { (self.glx.make_context_current)(display, p.draw, p.read, p.context) };
    }
}

impl GlxContext {
    /// The GL entry points of the process's GL (the app's libGL or libGLX).
    fn load_gl() -> Result<Gl, GlError> {
        Gl::from_process()
    }
}
