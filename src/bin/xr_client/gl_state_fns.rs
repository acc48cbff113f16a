//! The GL functions and the window system's (GLX, or EGL with `--gl-binding egl`) that
//! `--check-gl-state` ([`super::gl_state`]) calls, loaded once per run.

use crate::error::Result;
use crate::gl_binding::GlBinding;
use crate::gl_state_enums::Enum;
use crate::glx::GlContext;
use std::ffi::{c_char, c_int, c_void};

/// The first items: the current context, draw and read drawables.
pub const GLX_ITEMS: usize = 3;

pub type Create = unsafe extern "C" fn(i32, *mut u32);

/// The GL and GLX functions the check calls.
pub struct Fns {
    pub get_integer64v: unsafe extern "C" fn(Enum, *mut i64),
    pub get_integer64i_v: unsafe extern "C" fn(Enum, u32, *mut i64),
    pub is_enabled: unsafe extern "C" fn(Enum) -> u8,
    pub enable: unsafe extern "C" fn(Enum),
    pub disable: unsafe extern "C" fn(Enum),
    pub get_error: unsafe extern "C" fn() -> Enum,
    pub active_texture: unsafe extern "C" fn(Enum),
    pub bind_texture: unsafe extern "C" fn(Enum, u32),
    pub bind_textures: unsafe extern "C" fn(u32, i32, *const u32),
    pub bind_samplers: unsafe extern "C" fn(u32, i32, *const u32),
    pub bind_image_texture: unsafe extern "C" fn(u32, u32, i32, u8, i32, Enum, Enum),
    pub bind_image_textures: unsafe extern "C" fn(u32, i32, *const u32),
    pub bind_buffer: unsafe extern "C" fn(Enum, u32),
    pub bind_buffer_range: unsafe extern "C" fn(Enum, u32, u32, isize, isize),
    pub bind_buffers_base: unsafe extern "C" fn(Enum, u32, i32, *const u32),
    pub bind_framebuffer: unsafe extern "C" fn(Enum, u32),
    pub bind_renderbuffer: unsafe extern "C" fn(Enum, u32),
    pub bind_vertex_array: unsafe extern "C" fn(u32),
    pub use_program: unsafe extern "C" fn(u32),
    pub bind_program_pipeline: unsafe extern "C" fn(u32),
    pub pixel_store_i: unsafe extern "C" fn(Enum, i32),
    pub viewport: unsafe extern "C" fn(i32, i32, i32, i32),
    pub scissor: unsafe extern "C" fn(i32, i32, i32, i32),
    pub create_textures: unsafe extern "C" fn(Enum, i32, *mut u32),
    pub texture_storage_2d: unsafe extern "C" fn(u32, i32, Enum, i32, i32),
    pub texture_storage_3d: unsafe extern "C" fn(u32, i32, Enum, i32, i32, i32),
    pub create_samplers: Create,
    pub create_buffers: Create,
    pub named_buffer_storage: unsafe extern "C" fn(u32, isize, *const c_void, u32),
    pub create_framebuffers: Create,
    pub create_renderbuffers: Create,
    pub create_vertex_arrays: Create,
    pub create_program_pipelines: Create,
    pub create_shader_program_v: unsafe extern "C" fn(Enum, i32, *const *const c_char) -> u32,
    pub get_program_iv: unsafe extern "C" fn(u32, Enum, *mut i32),
    pub window_system: WindowSystem,
}

/// The window-system calls of the check: GLX's, or with --gl-binding egl EGL's (whose draw and
/// read surfaces stand for GLX's drawables, held as u64 as XIDs are).
pub enum WindowSystem {
    Glx {
        get_current_context: unsafe extern "C" fn() -> *mut c_void,
        get_current_drawable: unsafe extern "C" fn() -> u64,
        get_current_read_drawable: unsafe extern "C" fn() -> u64,
        make_context_current: unsafe extern "C" fn(*mut c_void, u64, u64, *mut c_void) -> c_int,
    },
    Egl {
        get_current_context: unsafe extern "C" fn() -> *mut c_void,
        get_current_surface: unsafe extern "C" fn(i32) -> *mut c_void,
        make_current:
            unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *mut c_void) -> u32,
    },
}

const EGL_DRAW: i32 = 0x3059;
const EGL_READ: i32 = 0x305A;

impl WindowSystem {
    pub fn load(gl: &GlContext) -> Result<WindowSystem> {
        // SAFETY: each field's type is the C type of the function named (glx.h, egl.h).
        unsafe {
            Ok(match gl.binding {
                GlBinding::Xlib => WindowSystem::Glx {
                    get_current_context: gl.glx_function(c"glXGetCurrentContext")?,
                    get_current_drawable: gl.glx_function(c"glXGetCurrentDrawable")?,
                    get_current_read_drawable: gl.glx_function(c"glXGetCurrentReadDrawable")?,
                    make_context_current: gl.glx_function(c"glXMakeContextCurrent")?,
                },
                GlBinding::Egl => WindowSystem::Egl {
                    get_current_context: gl.glx_function(c"eglGetCurrentContext")?,
                    get_current_surface: gl.glx_function(c"eglGetCurrentSurface")?,
                    make_current: gl.glx_function(c"eglMakeCurrent")?,
                },
            })
        }
    }

    /// The names of the current context, draw and read drawable queries (the GLX_ITEMS).
    pub fn names(&self) -> [&'static str; GLX_ITEMS] {
        match self {
            WindowSystem::Glx { .. } => [
                "glXGetCurrentContext",
                "glXGetCurrentDrawable",
                "glXGetCurrentReadDrawable",
            ],
            WindowSystem::Egl { .. } => [
                "eglGetCurrentContext",
                "eglGetCurrentSurface(EGL_DRAW)",
                "eglGetCurrentSurface(EGL_READ)",
            ],
        }
    }

    /// # Safety
    /// Queries of this thread's current context: always valid.
    pub unsafe fn current_context(&self) -> *mut c_void {
        // SAFETY: as the caller promises.
        unsafe {
            match self {
                WindowSystem::Glx {
                    get_current_context,
                    ..
                }
                | WindowSystem::Egl {
                    get_current_context,
                    ..
                } => get_current_context(),
            }
        }
    }

    /// # Safety
    /// As `current_context`.
    pub unsafe fn current_drawable(&self, read: bool) -> u64 {
        // SAFETY: as the caller promises.
        unsafe {
            match self {
                WindowSystem::Glx {
                    get_current_drawable,
                    get_current_read_drawable,
                    ..
                } => match read {
                    false => get_current_drawable(),
                    true => get_current_read_drawable(),
                },
                WindowSystem::Egl {
                    get_current_surface,
                    ..
                } => get_current_surface(if read { EGL_READ } else { EGL_DRAW }) as u64,
            }
        }
    }

    /// # Safety
    /// `display` and `context` the client's, `draw` and `read` drawables (or EGL surfaces) of
    /// its configuration.
    pub unsafe fn make_current(
        &self,
        display: *mut c_void,
        draw: u64,
        read: u64,
        context: *mut c_void,
    ) {
        // SAFETY: as the caller promises.
        unsafe {
            match self {
                WindowSystem::Glx {
                    make_context_current,
                    ..
                } => {
                    make_context_current(display, draw, read, context);
                }
                WindowSystem::Egl { make_current, .. } => {
                    make_current(display, draw as *mut c_void, read as *mut c_void, context);
                }
            }
        }
    }
}

impl Fns {
    pub fn load(gl: &GlContext) -> Result<Fns> {
        // SAFETY: each field's type is the C type of the function named (gl.h, glext.h, glx.h).
        unsafe {
            Ok(Fns {
                get_integer64v: gl.function(c"glGetInteger64v")?,
                get_integer64i_v: gl.function(c"glGetInteger64i_v")?,
                is_enabled: gl.function(c"glIsEnabled")?,
                enable: gl.function(c"glEnable")?,
                disable: gl.function(c"glDisable")?,
                get_error: gl.function(c"glGetError")?,
                active_texture: gl.function(c"glActiveTexture")?,
                bind_texture: gl.function(c"glBindTexture")?,
                bind_textures: gl.function(c"glBindTextures")?,
                bind_samplers: gl.function(c"glBindSamplers")?,
                bind_image_texture: gl.function(c"glBindImageTexture")?,
                bind_image_textures: gl.function(c"glBindImageTextures")?,
                bind_buffer: gl.function(c"glBindBuffer")?,
                bind_buffer_range: gl.function(c"glBindBufferRange")?,
                bind_buffers_base: gl.function(c"glBindBuffersBase")?,
                bind_framebuffer: gl.function(c"glBindFramebuffer")?,
                bind_renderbuffer: gl.function(c"glBindRenderbuffer")?,
                bind_vertex_array: gl.function(c"glBindVertexArray")?,
                use_program: gl.function(c"glUseProgram")?,
                bind_program_pipeline: gl.function(c"glBindProgramPipeline")?,
                pixel_store_i: gl.function(c"glPixelStorei")?,
                viewport: gl.function(c"glViewport")?,
                scissor: gl.function(c"glScissor")?,
                create_textures: gl.function(c"glCreateTextures")?,
                texture_storage_2d: gl.function(c"glTextureStorage2D")?,
                texture_storage_3d: gl.function(c"glTextureStorage3D")?,
                create_samplers: gl.function(c"glCreateSamplers")?,
                create_buffers: gl.function(c"glCreateBuffers")?,
                named_buffer_storage: gl.function(c"glNamedBufferStorage")?,
                create_framebuffers: gl.function(c"glCreateFramebuffers")?,
                create_renderbuffers: gl.function(c"glCreateRenderbuffers")?,
                create_vertex_arrays: gl.function(c"glCreateVertexArrays")?,
                create_program_pipelines: gl.function(c"glCreateProgramPipelines")?,
                create_shader_program_v: gl.function(c"glCreateShaderProgramv")?,
                get_program_iv: gl.function(c"glGetProgramiv")?,
                window_system: WindowSystem::load(gl)?,
            })
        }
    }
}
