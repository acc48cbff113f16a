//! The app's GLX context around the layer's GL calls, as the runtime does around its own: made
//! current on the calling thread when it is not, and what was current put back after. A
//! context current on another thread cannot be made current here: GLX raises an X error for
//! it, which Xlib's default handler turns into the app's exit. X error handlers are one per
//! process, so the layer's is installed at its first switch and kept (installed again when the
//! app has set another since): it takes only the errors of the layer's own requests, told by
//! their display and serial, one switch at a time, and hands every other error to the handler
//! it replaced. The app's errors, on any thread and display, reach the app's handler; nothing
//! is put back that could undo a handler another thread set meanwhile.

use super::app_context::{AppContext, Previous as AnyPrevious, NOT_CURRENT};
use crate::gpu::opengl::{Gl, GlError};
use std::cell::Cell;
use std::ffi::{c_int, c_ulong, c_void, CStr};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;

type Display = c_void;
type GetCurrentContext = unsafe extern "C" fn() -> *mut c_void;
type GetCurrentDrawable = unsafe extern "C" fn() -> u64;
type GetCurrentDisplay = unsafe extern "C" fn() -> *mut Display;
type MakeContextCurrent = unsafe extern "C" fn(*mut Display, u64, u64, *mut c_void) -> c_int;
type ErrorHandler = Option<unsafe extern "C" fn(*mut Display, *mut c_void) -> c_int>;
type SetErrorHandler = unsafe extern "C" fn(ErrorHandler) -> ErrorHandler;
type Sync = unsafe extern "C" fn(*mut Display, c_int) -> c_int;
type NextRequest = unsafe extern "C" fn(*mut Display) -> c_ulong;

/// libGLX's and libX11's entry points, from the libraries the app already loaded.
struct Glx {
    get_current_context: GetCurrentContext,
    get_current_drawable: GetCurrentDrawable,
    get_current_read_drawable: GetCurrentDrawable,
    get_current_display: GetCurrentDisplay,
    make_context_current: MakeContextCurrent,
    set_error_handler: SetErrorHandler,
    sync: Sync,
    next_request: NextRequest,
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
            next_request: function!(c"XNextRequest", X11, NextRequest),
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

/// XErrorEvent's first fields (Xlib.h): the display and serial tell whose request failed.
#[repr(C)]
struct XErrorEvent {
    kind: c_int,
    display: *mut Display,
    resource: c_ulong,
    serial: c_ulong,
}

/// The handler the layer's replaced, as an address (0: none yet); every error that is not the
/// layer's goes to it.
static CHAINED: AtomicUsize = AtomicUsize::new(0);
/// The display of the layer's switch under way (0: none), and the serials of its requests:
/// from `OWN_FIRST` up to, not including, `OWN_END`.
static OWN_DISPLAY: AtomicUsize = AtomicUsize::new(0);
static OWN_FIRST: AtomicU64 = AtomicU64::new(0);
static OWN_END: AtomicU64 = AtomicU64::new(0);
/// One switch at a time, so that the serials above are one switch's.
static SWITCH: Mutex<()> = Mutex::new(());

thread_local! {
    /// Set while this thread is inside the chained handler: a handler the app set later that
    /// hands its errors back to the layer's must not loop.
    static CHAINING: Cell<bool> = const { Cell::new(false) };
}

/// The layer's X error handler: an error of the layer's own switch (a bad drawable, a context
/// current elsewhere) is taken here, for Xlib's default would end the app, and whether the
/// switch worked is read from GLX afterwards; any other error goes to the handler in place
/// before the layer's (the app's, or Xlib's default), as if the layer were not there.
unsafe extern "C" fn layer_x_error(display: *mut Display, event: *mut c_void) -> c_int {
    // SAFETY: Xlib passes the error's event, an XErrorEvent.
    let serial: u64 = unsafe { (*event.cast::<XErrorEvent>()).serial };
    let own = display as usize == OWN_DISPLAY.load(Ordering::Acquire)
        && (OWN_FIRST.load(Ordering::Acquire)..OWN_END.load(Ordering::Acquire)).contains(&serial);
    if own || CHAINING.with(Cell::get) {
        return 0;
    }
    let chained = CHAINED.load(Ordering::Acquire);
    if chained == 0 {
        return 0;
    }
    // SAFETY: an address XSetErrorHandler returned, a handler of this C type that stays
    // loaded (Xlib's default or the app's).
    let handler = unsafe {
        std::mem::transmute::<usize, unsafe extern "C" fn(*mut Display, *mut c_void) -> c_int>(
            chained,
        )
    };
    CHAINING.with(|c| c.set(true));
    // SAFETY: the error as Xlib gave it to the layer's handler.
    let r = unsafe { handler(display, event) };
    CHAINING.with(|c| c.set(false));
    r
}

impl Glx {
    /// Makes `context` current on `display` with the layer's handler taking the errors of that
    /// call alone; Xlib's answer (0 when it failed).
    ///
    /// # Safety
    /// The binding's display, drawable and context, which the app keeps alive for the session.
    unsafe fn make_current_taking_errors(
        &self,
        display: *mut Display,
        drawable: u64,
        context: *mut c_void,
    ) -> c_int {
        let _one = SWITCH.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: the caller's contract. XSync first delivers the app's own pending errors to
        // whichever handler is in place; the layer's handler, once set, stays (set again if the
        // app set another since, which then gets the errors that are not the layer's).
        unsafe {
            (self.sync)(display, 0);
            let before = (self.set_error_handler)(Some(layer_x_error));
            if let Some(h) = before.filter(|&h| h as usize != layer_x_error as *const () as usize) {
                CHAINED.store(h as usize, Ordering::Release);
            }
            OWN_FIRST.store((self.next_request)(display), Ordering::Release);
            OWN_END.store(u64::MAX, Ordering::Release);
            OWN_DISPLAY.store(display as usize, Ordering::Release);
            let made = (self.make_context_current)(display, drawable, drawable, context);
            // Every error of the call has reached the handler when XSync returns.
            (self.sync)(display, 0);
            OWN_DISPLAY.store(0, Ordering::Release);
            made
        }
    }
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
        // the session.
        let made =
            unsafe { g.make_current_taking_errors(self.display, self.drawable, self.context) };
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
