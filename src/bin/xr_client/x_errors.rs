//! `--x-errors-elsewhere` (OpenGL, Xlib binding): an app whose X errors must reach its own
//! handler while a layer switches GL contexts. The client sets an X error handler that counts
//! the errors of a second X connection, which a thread of its own keeps making (a request on
//! an id no client has, then XSync, in a loop), and calls xrEndFrame with its context released
//! (not current on any thread, which OpenXR allows), so that a layer working in the app's
//! context makes it current and puts it back around every frame. The report gives the errors
//! made and the errors the handler saw: equal when nothing in the process swallowed one.

use crate::error::Result;
use crate::glx::{open, symbol, GlContext};
use std::ffi::{c_char, c_int, c_ulong, c_void};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

/// A resource id no client has (ids are 29 bits, and the server hands them out from a base per
/// client far below this).
const NO_SUCH_PIXMAP: c_ulong = 0x1fff_fff7;

type Handler = Option<unsafe extern "C" fn(*mut c_void, *mut c_void) -> c_int>;

/// The second connection's display, and the errors on it the handler saw.
static ERROR_DISPLAY: AtomicUsize = AtomicUsize::new(0);
static SEEN: AtomicU64 = AtomicU64::new(0);

unsafe extern "C" fn count_error(display: *mut c_void, _: *mut c_void) -> c_int {
    if display as usize == ERROR_DISPLAY.load(Ordering::Acquire) {
        SEEN.fetch_add(1, Ordering::Relaxed);
    }
    0
}

/// The libX11 and GLX calls made here.
#[derive(Clone, Copy)]
struct Fns {
    open_display: unsafe extern "C" fn(*const c_char) -> *mut c_void,
    close_display: unsafe extern "C" fn(*mut c_void) -> c_int,
    free_pixmap: unsafe extern "C" fn(*mut c_void, c_ulong) -> c_int,
    sync: unsafe extern "C" fn(*mut c_void, c_int) -> c_int,
    make_current: unsafe extern "C" fn(*mut c_void, u64, u64, *mut c_void) -> c_int,
}

/// The errors under way, and the client's context to release around xrEndFrame.
pub struct XErrors {
    fns: Fns,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<u64>>,
    display: *mut c_void,
    drawable: u64,
    context: *mut c_void,
}

impl XErrors {
    /// Sets the counting handler and starts the thread making errors.
    pub fn start(gl: &GlContext) -> Result<XErrors> {
        let x11 = open(c"libX11.so.6")?;
        let libgl = open(c"libGL.so.1")?;
        // SAFETY: each symbol is named with its C type (Xlib.h, glx.h).
        let (fns, set_handler) = unsafe {
            let set_handler: unsafe extern "C" fn(Handler) -> Handler =
                symbol(x11, c"XSetErrorHandler")?;
            let fns = Fns {
                open_display: symbol(x11, c"XOpenDisplay")?,
                close_display: symbol(x11, c"XCloseDisplay")?,
                free_pixmap: symbol(x11, c"XFreePixmap")?,
                sync: symbol(x11, c"XSync")?,
                make_current: symbol(libgl, c"glXMakeContextCurrent")?,
            };
            (fns, set_handler)
        };
        // SAFETY: a new connection to $DISPLAY, used by the thread below alone.
        let display = unsafe { (fns.open_display)(std::ptr::null()) };
        if display.is_null() {
            return crate::error::fail("--x-errors-elsewhere: cannot open a second X connection");
        }
        ERROR_DISPLAY.store(display as usize, Ordering::Release);
        // SAFETY: a handler of Xlib's C type, for the process.
        unsafe { set_handler(Some(count_error)) };
        let stop = Arc::new(AtomicBool::new(false));
        let (flag, raw) = (stop.clone(), display as usize);
        let thread = std::thread::spawn(move || {
            let display = raw as *mut c_void;
            let mut made = 0u64;
            while !flag.load(Ordering::Relaxed) {
                // SAFETY: this thread's own connection; the id is no one's (BadPixmap).
                unsafe {
                    (fns.free_pixmap)(display, NO_SUCH_PIXMAP);
                    (fns.sync)(display, 0);
                }
                made += 1;
            }
            made
        });
        Ok(XErrors {
            fns,
            stop,
            thread: Some(thread),
            display: gl.display,
            drawable: gl.drawable,
            context: gl.context,
        })
    }

    /// Releases the client's context from this thread (before xrEndFrame).
    pub fn release_context(&self) {
        // SAFETY: the client's display; releasing what is current is always allowed.
        unsafe { (self.fns.make_current)(self.display, 0, 0, std::ptr::null_mut()) };
    }

    /// Makes the client's context current again (after xrEndFrame).
    pub fn take_context(&self) -> Result<()> {
        // SAFETY: the client's display, pbuffer and context, current on no other thread.
        let made = unsafe {
            (self.fns.make_current)(self.display, self.drawable, self.drawable, self.context)
        };
        if made == 0 {
            return crate::error::fail("glXMakeContextCurrent failed after xrEndFrame");
        }
        Ok(())
    }

    /// Stops the thread: the errors it made, and those the handler saw.
    pub fn finish(mut self) -> (u64, u64) {
        self.stop.store(true, Ordering::Relaxed);
        let made = self.thread.take().map_or(0, |t| t.join().unwrap_or(0));
        let display = ERROR_DISPLAY.swap(0, Ordering::AcqRel) as *mut c_void;
        let seen = SEEN.load(Ordering::Relaxed);
        // SAFETY: the thread's connection, which nothing uses any more.
        unsafe { (self.fns.close_display)(display) };
        (made, seen)
    }
}
