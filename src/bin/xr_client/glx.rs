//! `--graphics opengl`: an OpenGL 4.5 core context on the X server in $DISPLAY through GLX, as
//! OpenGL apps on Linux make one for XR_KHR_opengl_enable's Xlib binding (libX11 and libGL
//! opened at run time, so the client builds without their development files), and the few GL
//! calls the client makes. With `--gl-binding egl` the context is egl.rs's instead; the GL
//! calls are the same.

use crate::error::{fail, Result};
use crate::gl_binding::GlBinding;
use std::ffi::{c_char, c_int, c_void, CStr};

// GLX and GL enums the client uses (glx.h, glext.h).
const GLX_X_RENDERABLE: c_int = 0x8012;
const GLX_DRAWABLE_TYPE: c_int = 0x8010;
const GLX_PBUFFER_BIT: c_int = 0x0004;
const GLX_WINDOW_BIT: c_int = 0x0001;
const GLX_RENDER_TYPE: c_int = 0x8011;
const GLX_RGBA_BIT: c_int = 0x0001;
const GLX_RED_SIZE: c_int = 8;
const GLX_GREEN_SIZE: c_int = 9;
const GLX_BLUE_SIZE: c_int = 10;
const GLX_ALPHA_SIZE: c_int = 11;
const GLX_PBUFFER_WIDTH: c_int = 0x8041;
const GLX_PBUFFER_HEIGHT: c_int = 0x8040;
const GLX_CONTEXT_MAJOR_VERSION_ARB: c_int = 0x2091;
const GLX_CONTEXT_MINOR_VERSION_ARB: c_int = 0x2092;
const GLX_CONTEXT_PROFILE_MASK_ARB: c_int = 0x9126;
const GLX_CONTEXT_CORE_PROFILE_BIT_ARB: c_int = 0x0001;
pub const GL_RGBA: u32 = 0x1908;
pub const GL_UNSIGNED_BYTE: u32 = 0x1401;
pub const GL_UNSIGNED_SHORT: u32 = 0x1403;
pub const GL_HALF_FLOAT: u32 = 0x140B;
const GL_FLOAT: u32 = 0x1406;
pub const GL_UNSIGNED_INT_2_10_10_10_REV: u32 = 0x8368;
const GL_UNPACK_ALIGNMENT: u32 = 0x0CF5;
const GL_PACK_ALIGNMENT: u32 = 0x0D05;
const GL_VERSION: u32 = 0x1F02;
const GL_RENDERER: u32 = 0x1F01;

/// The attributes of the client's pbuffers: 16x16.
const PBUFFER_SIZE: [c_int; 5] = [GLX_PBUFFER_WIDTH, 16, GLX_PBUFFER_HEIGHT, 16, 0];

/// The shape of a swapchain's GL texture.
#[derive(Clone, Copy, Debug)]
pub struct Texture {
    pub size: (u32, u32),
    pub layers: u32,
    /// GL_TEXTURE_2D_ARRAY (the runtime's texture for arraySize above 1), else GL_TEXTURE_2D.
    pub array: bool,
}

/// XVisualInfo's first fields (Xutil.h); only `visualid` is read.
#[repr(C)]
struct VisualInfo {
    visual: *mut c_void,
    visualid: std::ffi::c_ulong,
}

pub type GetProc = unsafe extern "C" fn(*const c_char) -> *mut c_void;
type CreateContextAttribs =
    unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, c_int, *const c_int) -> *mut c_void;

/// The GL functions the client calls (through glXGetProcAddressARB).
struct Gl {
    texture_sub_image_2d:
        unsafe extern "C" fn(u32, i32, i32, i32, i32, i32, u32, u32, *const c_void),
    clear_tex_image: unsafe extern "C" fn(u32, i32, u32, u32, *const c_void),
    texture_sub_image_3d:
        unsafe extern "C" fn(u32, i32, i32, i32, i32, i32, i32, i32, u32, u32, *const c_void),
    get_texture_sub_image:
        unsafe extern "C" fn(u32, i32, i32, i32, i32, i32, i32, i32, u32, u32, i32, *mut c_void),
    pixel_store_i: unsafe extern "C" fn(u32, i32),
    get_error: unsafe extern "C" fn() -> u32,
    get_string: unsafe extern "C" fn(u32) -> *const u8,
}

/// A current GL context on a 16x16 pbuffer of its own, and what the session's binding needs.
pub struct GlContext {
    /// Which binding the handles below are for: GLX's (Xlib) or EGL's.
    pub binding: GlBinding,
    /// The X display, or the EGLDisplay.
    pub display: *mut c_void,
    /// The GLXFBConfig, or the EGLConfig.
    pub fb_config: *mut c_void,
    /// The X visual (0 with EGL).
    pub visual_id: u32,
    /// The GLX pbuffer, or the EGLSurface of the EGL pbuffer (which the binding does not take).
    pub drawable: u64,
    /// The GLXContext, or the EGLContext.
    pub context: *mut c_void,
    gl: Gl,
    /// libGL (GLX) or libEGL.
    libgl: *mut c_void,
    /// glXGetProcAddressARB, or eglGetProcAddress.
    get_proc: GetProc,
}

/// A library of the system, opened once (never closed: GL drivers do not support it).
pub fn open(name: &CStr) -> Result<*mut c_void> {
    // SAFETY: dlopen with a NUL-terminated name.
    let handle = unsafe { libc::dlopen(name.as_ptr(), libc::RTLD_NOW | libc::RTLD_GLOBAL) };
    if handle.is_null() {
        return fail(format!("cannot open {}", name.to_string_lossy()));
    }
    Ok(handle)
}

/// A symbol of `lib` as a function pointer of type T.
///
/// # Safety
/// T must be the symbol's C function pointer type.
pub unsafe fn symbol<T: Copy>(lib: *mut c_void, name: &CStr) -> Result<T> {
    // SAFETY: a handle from dlopen and a NUL-terminated name.
    let p = unsafe { libc::dlsym(lib, name.as_ptr()) };
    if p.is_null() {
        return fail(format!(
            "no {} in libGL/libX11/libEGL",
            name.to_string_lossy()
        ));
    }
    // SAFETY: the caller names the symbol's type; function pointers are pointer-sized.
    Ok(unsafe { std::mem::transmute_copy(&p) })
}

/// A GL function through glXGetProcAddressARB (or eglGetProcAddress).
///
/// # Safety
/// T must be the function's C pointer type.
unsafe fn gl_fn<T: Copy>(get: GetProc, name: &CStr) -> Result<T> {
    // SAFETY: a NUL-terminated name; GLX returns null or the function.
    let p = unsafe { get(name.as_ptr()) };
    if p.is_null() {
        return fail(format!("the GL driver has no {}", name.to_string_lossy()));
    }
    // SAFETY: the caller names the function's type.
    Ok(unsafe { std::mem::transmute_copy(&p) })
}

impl GlContext {
    /// Opens $DISPLAY and makes a GL 4.5 core context current on this thread.
    pub fn new() -> Result<GlContext> {
        let x11 = open(c"libX11.so.6")?;
        let libgl = open(c"libGL.so.1")?;
        // SAFETY: each symbol is named with its C type (Xlib.h, glx.h).
        unsafe {
            let open_display: unsafe extern "C" fn(*const c_char) -> *mut c_void =
                symbol(x11, c"XOpenDisplay")?;
            let default_screen: unsafe extern "C" fn(*mut c_void) -> c_int =
                symbol(x11, c"XDefaultScreen")?;
            let choose: unsafe extern "C" fn(
                *mut c_void,
                c_int,
                *const c_int,
                *mut c_int,
            ) -> *mut *mut c_void = symbol(libgl, c"glXChooseFBConfig")?;
            let visual_of: unsafe extern "C" fn(*mut c_void, *mut c_void) -> *mut VisualInfo =
                symbol(libgl, c"glXGetVisualFromFBConfig")?;
            let create_pbuffer: unsafe extern "C" fn(
                *mut c_void,
                *mut c_void,
                *const c_int,
            ) -> u64 = symbol(libgl, c"glXCreatePbuffer")?;
            let make_current: unsafe extern "C" fn(*mut c_void, u64, u64, *mut c_void) -> c_int =
                symbol(libgl, c"glXMakeContextCurrent")?;
            let get_proc: GetProc = symbol(libgl, c"glXGetProcAddressARB")?;
            let display = open_display(std::ptr::null());
            if display.is_null() {
                return fail(
                    "cannot open the X display ($DISPLAY): --graphics opengl needs an X server",
                );
            }
            let attributes = [
                GLX_X_RENDERABLE,
                1,
                GLX_DRAWABLE_TYPE,
                GLX_PBUFFER_BIT | GLX_WINDOW_BIT,
                GLX_RENDER_TYPE,
                GLX_RGBA_BIT,
                GLX_RED_SIZE,
                8,
                GLX_GREEN_SIZE,
                8,
                GLX_BLUE_SIZE,
                8,
                GLX_ALPHA_SIZE,
                8,
                0,
            ];
            let mut count = 0;
            let configs = choose(
                display,
                default_screen(display),
                attributes.as_ptr(),
                &mut count,
            );
            if configs.is_null() || count == 0 {
                return fail("no GLX framebuffer configuration with RGBA8 and pbuffers");
            }
            let fb_config = *configs;
            let visual = visual_of(display, fb_config);
            if visual.is_null() {
                return fail("the GLX framebuffer configuration has no X visual");
            }
            let visual_id = (*visual).visualid as u32;
            let drawable = create_pbuffer(display, fb_config, PBUFFER_SIZE.as_ptr());
            let create_context: CreateContextAttribs =
                gl_fn(get_proc, c"glXCreateContextAttribsARB")?;
            let version = [
                GLX_CONTEXT_MAJOR_VERSION_ARB,
                4,
                GLX_CONTEXT_MINOR_VERSION_ARB,
                5,
                GLX_CONTEXT_PROFILE_MASK_ARB,
                GLX_CONTEXT_CORE_PROFILE_BIT_ARB,
                0,
            ];
            let context = create_context(
                display,
                fb_config,
                std::ptr::null_mut(),
                1,
                version.as_ptr(),
            );
            if context.is_null() || drawable == 0 {
                return fail("cannot create a GL 4.5 core context on a GLX pbuffer");
            }
            if make_current(display, drawable, drawable, context) == 0 {
                return fail("glXMakeContextCurrent failed");
            }
            GlContext::current(
                GlBinding::Xlib,
                (display, fb_config, context),
                libgl,
                get_proc,
            )
            .map(|gl| GlContext {
                visual_id,
                drawable,
                ..gl
            })
        }
    }

    /// The context `handles` (display, configuration, context) of `binding`, current on this
    /// thread, with the client's GL functions loaded through `get_proc` and its pixel store set.
    ///
    /// # Safety
    /// The context must be current on this thread; `lib` a dlopen handle of its GLX or EGL
    /// library and `get_proc` that library's glXGetProcAddressARB or eglGetProcAddress.
    pub unsafe fn current(
        binding: GlBinding,
        (display, fb_config, context): (*mut c_void, *mut c_void, *mut c_void),
        lib: *mut c_void,
        get_proc: GetProc,
    ) -> Result<GlContext> {
        // SAFETY: each function is named with its C type (glcorearb.h); the context is current.
        unsafe {
            let gl = Gl {
                texture_sub_image_2d: gl_fn(get_proc, c"glTextureSubImage2D")?,
                clear_tex_image: gl_fn(get_proc, c"glClearTexImage")?,
                texture_sub_image_3d: gl_fn(get_proc, c"glTextureSubImage3D")?,
                get_texture_sub_image: gl_fn(get_proc, c"glGetTextureSubImage")?,
                pixel_store_i: gl_fn(get_proc, c"glPixelStorei")?,
                get_error: gl_fn(get_proc, c"glGetError")?,
                get_string: gl_fn(get_proc, c"glGetString")?,
            };
            (gl.pixel_store_i)(GL_UNPACK_ALIGNMENT, 1);
            (gl.pixel_store_i)(GL_PACK_ALIGNMENT, 1);
            Ok(GlContext {
                binding,
                display,
                fb_config,
                visual_id: 0,
                drawable: 0,
                context,
                gl,
                libgl: lib,
                get_proc,
            })
        }
    }

    /// The loader of the context's GL functions (glXGetProcAddressARB or eglGetProcAddress).
    pub fn get_proc_address(&self) -> GetProc {
        self.get_proc
    }

    /// A GL function of the context's driver (through glXGetProcAddressARB or eglGetProcAddress).
    ///
    /// # Safety
    /// T must be the function's C pointer type.
    pub unsafe fn function<T: Copy>(&self, name: &CStr) -> Result<T> {
        // SAFETY: the caller names the function's type.
        unsafe { gl_fn(self.get_proc, name) }
    }

    /// A GLX function of libGL (or with EGL an EGL function of libEGL).
    ///
    /// # Safety
    /// T must be the function's C pointer type.
    pub unsafe fn glx_function<T: Copy>(&self, name: &CStr) -> Result<T> {
        // SAFETY: the caller names the function's type.
        unsafe { symbol(self.libgl, name) }
    }

    /// Another 16x16 GLX pbuffer on the context's framebuffer configuration (with EGL:
    /// `egl::pbuffer`).
    pub fn glx_pbuffer(&self) -> Result<u64> {
        // SAFETY: glXCreatePbuffer's type (glx.h); the display and configuration are the
        // context's own and the attribute list ends with 0.
        unsafe {
            let create_pbuffer: unsafe extern "C" fn(
                *mut c_void,
                *mut c_void,
                *const c_int,
            ) -> u64 = self.glx_function(c"glXCreatePbuffer")?;
            match create_pbuffer(self.display, self.fb_config, PBUFFER_SIZE.as_ptr()) {
                0 => fail("glXCreatePbuffer failed"),
                drawable => Ok(drawable),
            }
        }
    }

    /// "version, renderer" of the current context.
    pub fn describe(&self) -> String {
        let text = |name| {
            // SAFETY: the context is current; glGetString returns a static string or null.
            let p = unsafe { (self.gl.get_string)(name) };
            match p.is_null() {
                true => String::new(),
                // SAFETY: a NUL-terminated string owned by the driver.
                false => unsafe { CStr::from_ptr(p.cast()) }
                    .to_string_lossy()
                    .into_owned(),
            }
        };
        format!("{}, {}", text(GL_VERSION), text(GL_RENDERER))
    }

    /// Writes `bytes` (layer after layer, rows bottom first, tightly packed) into every layer of
    /// texture `image`: a 2D array texture of `texture.layers`, or with `texture.array` false a
    /// 2D texture (a swapchain of arraySize 1).
    pub fn upload(
        &self,
        image: u32,
        texture: Texture,
        (format, ty): (u32, u32),
        bytes: &[u8],
    ) -> Result<()> {
        let (w, h) = (texture.size.0 as i32, texture.size.1 as i32);
        // SAFETY: the context is current; `bytes` holds w x h x layers texels of (format, ty)
        // with alignment 1 (set at creation).
        unsafe {
            if texture.array {
                let layers = texture.layers as i32;
                (self.gl.texture_sub_image_3d)(
                    image,
                    0,
                    0,
                    0,
                    0,
                    w,
                    h,
                    layers,
                    format,
                    ty,
                    bytes.as_ptr().cast(),
                );
            } else {
                (self.gl.texture_sub_image_2d)(
                    image,
                    0,
                    0,
                    0,
                    w,
                    h,
                    format,
                    ty,
                    bytes.as_ptr().cast(),
                );
            }
        }
        self.check(match texture.array {
            true => "glTextureSubImage3D",
            false => "glTextureSubImage2D",
        })
    }

    /// Reads every layer of texture `image` (layer after layer, rows bottom first) into `out`
    /// (resized).
    pub fn read(
        &self,
        image: u32,
        texture: Texture,
        (format, ty): (u32, u32),
        out: &mut Vec<u8>,
        texel_bytes: usize,
    ) -> Result<()> {
        let (w, h) = texture.size;
        out.resize(
            w as usize * h as usize * texture.layers as usize * texel_bytes,
            0,
        );
        // SAFETY: the context is current; `out` holds exactly the bytes asked for.
        unsafe {
            (self.gl.get_texture_sub_image)(
                image,
                0,
                0,
                0,
                0,
                w as i32,
                h as i32,
                texture.layers as i32,
                format,
                ty,
                out.len() as i32,
                out.as_mut_ptr().cast(),
            );
        }
        self.check("glGetTextureSubImage")
    }

    /// Clears every layer of texture `image` to `rgba`.
    pub fn clear(&self, image: u32, rgba: [f32; 4]) -> Result<()> {
        // SAFETY: the context is current; four floats for (GL_RGBA, GL_FLOAT).
        unsafe { (self.gl.clear_tex_image)(image, 0, GL_RGBA, GL_FLOAT, rgba.as_ptr().cast()) };
        self.check("glClearTexImage")
    }

    fn check(&self, call: &str) -> Result<()> {
        // SAFETY: the context is current.
        match unsafe { (self.gl.get_error)() } {
            0 => Ok(()),
            e => fail(format!("{call} failed: GL error 0x{e:04x}")),
        }
    }
}
