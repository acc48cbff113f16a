//! `--graphics opengl --gl-binding egl`: an OpenGL 4.5 core context made with EGL, as apps that
//! use XR_MNDX_egl_enable make one: libEGL.so.1 opened at run time, Mesa's surfaceless platform
//! (no window system needed), a configuration that renders OpenGL into pbuffers, the context
//! current on a 16x16 pbuffer of its own, and the session on it (its binding chained by hand).
//! With `--egl-bind-es` the thread has EGL_OPENGL_ES_API bound around xrEndFrame. The GL calls
//! are glx.rs's.

use crate::error::{fail, Result};
use crate::gl_binding::GlBinding;
use crate::glx::{self, GetProc, GlContext};
use openxr as xr;
use openxr::sys;
use std::ffi::c_void;

// EGL enums (egl.h, eglext.h).
const PLATFORM_SURFACELESS_MESA: u32 = 0x31DD;
const OPENGL_API: u32 = 0x30A2;
const OPENGL_ES_API: u32 = 0x30A0;
const SURFACE_TYPE: i32 = 0x3033;
const PBUFFER_BIT: i32 = 0x0001;
const RENDERABLE_TYPE: i32 = 0x3040;
const OPENGL_BIT: i32 = 0x0008;
const RED_SIZE: i32 = 0x3024;
const GREEN_SIZE: i32 = 0x3023;
const BLUE_SIZE: i32 = 0x3022;
const ALPHA_SIZE: i32 = 0x3021;
const WIDTH: i32 = 0x3057;
const HEIGHT: i32 = 0x3056;
const CONTEXT_MAJOR_VERSION: i32 = 0x3098;
const CONTEXT_MINOR_VERSION: i32 = 0x30FB;
const CONTEXT_OPENGL_PROFILE_MASK: i32 = 0x30FD;
const CONTEXT_OPENGL_CORE_PROFILE_BIT: i32 = 1;
const NONE: i32 = 0x3038;

/// The attributes of the client's pbuffers: 16x16.
const PBUFFER_SIZE: [i32; 5] = [WIDTH, 16, HEIGHT, 16, NONE];

type GetPlatformDisplay = unsafe extern "C" fn(u32, *mut c_void, *const i32) -> *mut c_void;
type Initialize = unsafe extern "C" fn(*mut c_void, *mut i32, *mut i32) -> u32;
type BindApi = unsafe extern "C" fn(u32) -> u32;
type ChooseConfig =
    unsafe extern "C" fn(*mut c_void, *const i32, *mut *mut c_void, i32, *mut i32) -> u32;
type CreatePbufferSurface =
    unsafe extern "C" fn(*mut c_void, *mut c_void, *const i32) -> *mut c_void;
type CreateContext =
    unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *const i32) -> *mut c_void;
type MakeCurrent = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *mut c_void) -> u32;
type QueryApi = unsafe extern "C" fn() -> u32;

/// Makes an EGL OpenGL 4.5 core context current on this thread (never destroyed: the client
/// keeps its context for the process, as with GLX).
pub fn context() -> Result<GlContext> {
    let lib = glx::open(c"libEGL.so.1")?;
    // SAFETY: each symbol is libEGL's function of the C type it is read as (egl.h); every
    // attribute list ends with EGL_NONE; the handles passed are the ones EGL returned.
    unsafe {
        let get_proc: GetProc = glx::symbol(lib, c"eglGetProcAddress")?;
        let initialize: Initialize = glx::symbol(lib, c"eglInitialize")?;
        let bind_api: BindApi = glx::symbol(lib, c"eglBindAPI")?;
        let choose: ChooseConfig = glx::symbol(lib, c"eglChooseConfig")?;
        let create_pbuffer: CreatePbufferSurface = glx::symbol(lib, c"eglCreatePbufferSurface")?;
        let create_context: CreateContext = glx::symbol(lib, c"eglCreateContext")?;
        let make_current: MakeCurrent = glx::symbol(lib, c"eglMakeCurrent")?;
        let platform = get_proc(c"eglGetPlatformDisplayEXT".as_ptr());
        if platform.is_null() {
            return fail("EGL has no eglGetPlatformDisplayEXT (EGL_EXT_platform_base)");
        }
        let platform: GetPlatformDisplay = std::mem::transmute(platform);
        let display = platform(
            PLATFORM_SURFACELESS_MESA,
            std::ptr::null_mut(),
            std::ptr::null(),
        );
        let (mut major, mut minor) = (0, 0);
        if display.is_null() || initialize(display, &mut major, &mut minor) == 0 {
            return fail(
                "EGL's surfaceless platform (EGL_MESA_platform_surfaceless) is not available",
            );
        }
        if bind_api(OPENGL_API) == 0 {
            return fail("eglBindAPI(EGL_OPENGL_API) failed");
        }
        let attributes = [
            SURFACE_TYPE,
            PBUFFER_BIT,
            RENDERABLE_TYPE,
            OPENGL_BIT,
            RED_SIZE,
            8,
            GREEN_SIZE,
            8,
            BLUE_SIZE,
            8,
            ALPHA_SIZE,
            8,
            NONE,
        ];
        let (mut config, mut count) = (std::ptr::null_mut(), 0);
        if choose(display, attributes.as_ptr(), &mut config, 1, &mut count) == 0 || count == 0 {
            return fail("no EGL configuration with RGBA8, OpenGL and pbuffers");
        }
        let surface = create_pbuffer(display, config, PBUFFER_SIZE.as_ptr());
        let version = [
            CONTEXT_MAJOR_VERSION,
            4,
            CONTEXT_MINOR_VERSION,
            5,
            CONTEXT_OPENGL_PROFILE_MASK,
            CONTEXT_OPENGL_CORE_PROFILE_BIT,
            NONE,
        ];
        let context = create_context(display, config, std::ptr::null_mut(), version.as_ptr());
        if context.is_null() || surface.is_null() {
            return fail("cannot create an EGL OpenGL 4.5 core context on a pbuffer");
        }
        if make_current(display, surface, surface, context) == 0 {
            return fail("eglMakeCurrent failed");
        }
        let mut gl = GlContext::current(GlBinding::Egl, (display, config, context), lib, get_proc)?;
        gl.drawable = surface as u64;
        Ok(gl)
    }
}

/// Another 16x16 pbuffer on `gl`'s EGL configuration, as u64 (--check-gl-state's drawables).
pub fn pbuffer(gl: &GlContext) -> Result<u64> {
    // SAFETY: eglCreatePbufferSurface's type (egl.h); the display and configuration are the
    // context's own and the attribute list ends with EGL_NONE.
    unsafe {
        let create: CreatePbufferSurface = gl.glx_function(c"eglCreatePbufferSurface")?;
        match create(gl.display, gl.fb_config, PBUFFER_SIZE.as_ptr()) {
            surface if surface.is_null() => fail("eglCreatePbufferSurface failed"),
            surface => Ok(surface as u64),
        }
    }
}

/// --egl-bind-es: EGL_OPENGL_ES_API bound on the client's thread with its OpenGL context
/// current, as an app that also draws with OpenGL ES may leave it (EGL's default API on a
/// thread that never bound one), before every xrEndFrame, and eglQueryAPI read after it.
pub struct EsBound {
    bind_api: BindApi,
    query_api: QueryApi,
    /// The xrEndFrame calls after which the API was read.
    pub checked: u32,
    /// The frames after which it was another API.
    pub changed: Vec<u32>,
}

impl EsBound {
    /// Binds EGL_OPENGL_ES_API on this thread, whose current OpenGL context is `gl`.
    pub fn bind(gl: &GlContext) -> Result<EsBound> {
        // SAFETY: eglBindAPI's and eglQueryAPI's types (egl.h); binding an API changes which
        // API's context eglGetCurrent* name, not which contexts are current.
        unsafe {
            let bind_api: BindApi = gl.glx_function(c"eglBindAPI")?;
            let query_api: QueryApi = gl.glx_function(c"eglQueryAPI")?;
            if bind_api(OPENGL_ES_API) == 0 || query_api() != OPENGL_ES_API {
                return fail("eglBindAPI(EGL_OPENGL_ES_API) failed");
            }
            Ok(EsBound {
                bind_api,
                query_api,
                checked: 0,
                changed: Vec::new(),
            })
        }
    }

    /// Binds EGL_OPENGL_ES_API again before xrEndFrame, as an app that draws with OpenGL
    /// ES between frames leaves it: the runtime's other calls may bind EGL_OPENGL_API on the
    /// thread (Monado's do, before the first frame), and the check is of xrEndFrame's.
    pub fn bind_again(&self) {
        // SAFETY: eglBindAPI of an API this thread bound before.
        unsafe { (self.bind_api)(OPENGL_ES_API) };
    }

    /// Reads the bound API after xrEndFrame of `frame`.
    pub fn check(&mut self, frame: u32) {
        // SAFETY: eglQueryAPI reads this thread's bound API.
        let api = unsafe { (self.query_api)() };
        self.checked += 1;
        if api != OPENGL_ES_API {
            self.changed.push(frame);
        }
    }
}

/// A session on an OpenGL context, with its frame waiter and stream.
pub type GlSessionParts = (
    xr::Session<xr::OpenGL>,
    xr::FrameWaiter,
    xr::FrameStream<xr::OpenGL>,
);

/// The session on an EGL context (XR_MNDX_egl_enable). The openxr crate has no session type for
/// it: xrCreateSession with the binding chained by hand, the session then used as any OpenGL
/// one (its swapchain images are XrSwapchainImageOpenGLKHR).
pub fn create_session(
    instance: &xr::Instance,
    system: xr::SystemId,
    gl: &GlContext,
) -> Result<GlSessionParts> {
    let get_proc = gl.get_proc_address();
    let binding = sys::GraphicsBindingEGLMNDX {
        ty: sys::GraphicsBindingEGLMNDX::TYPE,
        next: std::ptr::null(),
        // SAFETY: eglGetProcAddress has the C type of PFN_xrEglGetProcAddressMNDX (a name in, a
        // function pointer or null out).
        get_proc_address: Some(unsafe {
            std::mem::transmute::<crate::glx::GetProc, sys::platform::EglGetProcAddressMNDX>(
                get_proc,
            )
        }),
        display: gl.display,
        config: gl.fb_config,
        context: gl.context,
    };
    let info = sys::SessionCreateInfo {
        ty: sys::SessionCreateInfo::TYPE,
        next: (&binding as *const sys::GraphicsBindingEGLMNDX).cast(),
        create_flags: sys::SessionCreateFlags::EMPTY,
        system_id: system,
    };
    let mut handle = sys::Session::NULL;
    // SAFETY: a valid create info whose chain lives across the call; the EGL objects are this
    // thread's current context and outlive the session.
    let result = unsafe { (instance.fp().create_session)(instance.as_raw(), &info, &mut handle) };
    if result.into_raw() < 0 {
        return fail(format!(
            "xrCreateSession (XrGraphicsBindingEGLMNDX) failed: {result}"
        ));
    }
    // SAFETY: a session of this instance just created with an OpenGL-family binding, owned by
    // the returned Session, which destroys it.
    Ok(unsafe { xr::Session::from_raw(instance.clone(), handle, Box::new(())) })
}
