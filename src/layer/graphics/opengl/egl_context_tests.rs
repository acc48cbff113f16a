//! Tests of egl_context.rs against an EGL of the test's own that does what EGL 1.5 says and
//! Mesa does not: each thread has one current context per client API, and eglGetCurrent* and
//! a releasing eglMakeCurrent act on the bound API's (Mesa keeps one current context for all
//! APIs, so the sandbox's EGL runs of tests/opengl_egl.rs cannot tell the two apart).

use super::*;
use std::cell::RefCell;
use std::collections::HashMap;
use std::ffi::c_char;

const ES_API: u32 = 0x30A0;
const SUCCESS: i32 = 0x3000;
const BAD_ACCESS: i32 = 0x3002;
const BAD_MATCH: i32 = 0x3009;
const BAD_PARAMETER: i32 = 0x300C;
const DISPLAY: usize = 0xd15;
/// The app's OpenGL context (the session's) and an OpenGL ES context of its own.
const APP_GL: usize = 0x61;
const APP_ES: usize = 0xe5;
const GL_PBUFFER: usize = 0xb1;
const ES_PBUFFER: usize = 0xb2;

/// One API's current context and surfaces on the thread.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
struct Bound {
    display: usize,
    draw: usize,
    read: usize,
    context: usize,
}

/// The thread's EGL state.
#[derive(Clone, PartialEq, Debug)]
struct Thread {
    api: u32,
    current: HashMap<u32, Bound>,
    error: i32,
}

thread_local! {
    static THREAD: RefCell<Thread> = RefCell::new(Thread {
        api: ES_API,
        current: HashMap::new(),
        error: SUCCESS,
    });
    /// The app's OpenGL context is current on another thread: it cannot be made current.
    static BUSY: RefCell<bool> = const { RefCell::new(false) };
}

/// `f` on this thread's EGL state, the call's error set to what it returns.
fn call<T>(f: impl FnOnce(&mut Thread) -> Result<T, (i32, T)>) -> T {
    THREAD.with_borrow_mut(|t| match f(t) {
        Ok(v) => {
            t.error = SUCCESS;
            v
        }
        Err((e, v)) => {
            t.error = e;
            v
        }
    })
}

fn bound(t: &Thread) -> Bound {
    t.current.get(&t.api).copied().unwrap_or_default()
}

extern "C" fn get_current_context() -> *mut c_void {
    call(|t| Ok(bound(t).context as *mut c_void))
}

extern "C" fn get_current_display() -> *mut c_void {
    call(|t| Ok(bound(t).display as *mut c_void))
}

extern "C" fn get_current_surface(which: i32) -> *mut c_void {
    call(|t| match which {
        DRAW => Ok(bound(t).draw as *mut c_void),
        _ => Ok(bound(t).read as *mut c_void),
    })
}

extern "C" fn make_current(d: *mut c_void, dr: *mut c_void, r: *mut c_void, c: *mut c_void) -> u32 {
    let (display, draw, read, context) = (d as usize, dr as usize, r as usize, c as usize);
    call(|t| {
        if context == APP_GL && BUSY.with_borrow(|b| *b) {
            return Err((BAD_ACCESS, 0));
        }
        if context == 0 {
            if draw != 0 || read != 0 {
                return Err((BAD_MATCH, 0));
            }
            // Releasing acts on the bound API's context.
            t.current.remove(&t.api);
            return Ok(1);
        }
        // Binding a context acts on the context's own API.
        let api = if context == APP_ES {
            ES_API
        } else {
            OPENGL_API
        };
        let b = Bound {
            display,
            draw,
            read,
            context,
        };
        t.current.insert(api, b);
        Ok(1)
    })
}

extern "C" fn query_api() -> u32 {
    call(|t| Ok(t.api))
}

extern "C" fn bind_api(api: u32) -> u32 {
    call(|t| match api {
        OPENGL_API | ES_API => {
            t.api = api;
            Ok(1)
        }
        _ => Err((BAD_PARAMETER, 0)),
    })
}

extern "C" fn get_error() -> i32 {
    THREAD.with_borrow_mut(|t| std::mem::replace(&mut t.error, SUCCESS))
}

/// The fake EGL's eglGetProcAddress.
unsafe extern "system" fn get_proc(name: *const c_char) -> Option<unsafe extern "system" fn()> {
    // SAFETY: the layer passes NUL-terminated names.
    let name = unsafe { CStr::from_ptr(name) }.to_str().unwrap();
    let f = match name {
        "eglGetCurrentContext" => get_current_context as *const (),
        "eglGetCurrentDisplay" => get_current_display as *const (),
        "eglGetCurrentSurface" => get_current_surface as *const (),
        "eglMakeCurrent" => make_current as *const (),
        "eglQueryAPI" => query_api as *const (),
        "eglBindAPI" => bind_api as *const (),
        "eglGetError" => get_error as *const (),
        _ => return None,
    };
    // SAFETY: a function pointer, called back as the C type of the function named.
    Some(unsafe { std::mem::transmute::<*const (), unsafe extern "system" fn()>(f) })
}

/// The layer's view of the app's OpenGL context on the fake EGL.
fn app_context() -> EglContext {
    let binding = xr::GraphicsBindingEGLMNDX {
        ty: xr::GraphicsBindingEGLMNDX::TYPE,
        next: std::ptr::null(),
        get_proc_address: Some(get_proc),
        display: DISPLAY as *mut c_void,
        config: std::ptr::null_mut(),
        context: APP_GL as *mut c_void,
    };
    EglContext::new(&binding).unwrap()
}

/// The thread with `api` bound and these contexts current (on a pbuffer each).
fn set_thread(api: u32, contexts: &[usize]) -> Thread {
    let on = |context, pbuffer| Bound {
        display: DISPLAY,
        draw: pbuffer,
        read: pbuffer,
        context,
    };
    let mut current = HashMap::new();
    for &c in contexts {
        match c {
            APP_ES => current.insert(ES_API, on(APP_ES, ES_PBUFFER)),
            _ => current.insert(OPENGL_API, on(c, GL_PBUFFER)),
        };
    }
    let t = Thread {
        api,
        current,
        error: SUCCESS,
    };
    THREAD.set(t.clone());
    t
}

fn thread() -> Thread {
    THREAD.with_borrow(Thread::clone)
}

/// The layer's work in the app's context: entered, checked current for OpenGL, left.
fn enter_and_leave(context: &EglContext) -> Result<(), String> {
    let previous = context.enter()?;
    let t = thread();
    assert_eq!(t.current[&OPENGL_API].context, APP_GL, "{t:?}");
    context.leave(previous);
    Ok(())
}

/// The app's OpenGL context current (on its pbuffer) while the thread has OpenGL ES bound,
/// with an ES context current too: the layer finds its context current and switches nothing;
/// the app finds the API it bound and both contexts on their surfaces after.
#[test]
fn the_app_context_current_with_es_bound_is_used_as_it_is() {
    let context = app_context();
    for contexts in [&[APP_GL][..], &[APP_GL, APP_ES]] {
        let before = set_thread(ES_API, contexts);
        enter_and_leave(&context).unwrap();
        assert_eq!(thread(), before);
    }
}

/// The app's OpenGL context not current, OpenGL ES bound (and an ES context current or
/// none): the layer makes its context current for its work, and the thread gets back no
/// OpenGL context, its ES one, and the API it bound.
#[test]
fn the_app_context_made_current_under_es_is_released_after() {
    let context = app_context();
    for contexts in [&[][..], &[APP_ES]] {
        let before = set_thread(ES_API, contexts);
        enter_and_leave(&context).unwrap();
        assert_eq!(thread(), before);
    }
}

/// With EGL_OPENGL_API bound and the context current the layer has nothing to put back; with
/// another OpenGL context current it switches and switches back.
#[test]
fn with_opengl_bound_the_context_is_switched_only_when_not_current() {
    let context = app_context();
    set_thread(OPENGL_API, &[APP_GL]);
    assert!(context.enter().unwrap().is_none());
    let other = 0x07;
    let before = set_thread(OPENGL_API, &[other, APP_ES]);
    enter_and_leave(&context).unwrap();
    assert_eq!(thread(), before);
}

/// The app's context current on another thread: the switch fails, the thread keeps what it
/// had and the API it bound, and eglGetError says nothing of the layer's failed call.
#[test]
fn a_failed_switch_leaves_the_thread_as_it_was_with_no_egl_error() {
    let context = app_context();
    BUSY.set(true);
    for (api, contexts) in [(ES_API, &[APP_ES][..]), (OPENGL_API, &[0x07, APP_ES])] {
        let before = set_thread(api, contexts);
        let why = context.enter().map(|_| ()).unwrap_err();
        assert!(why.starts_with(NOT_CURRENT), "{why}");
        assert_eq!(thread(), before);
        assert_eq!(get_error(), SUCCESS);
    }
    BUSY.set(false);
}
