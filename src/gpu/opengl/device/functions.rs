//! The GL entry points the backend calls, loaded once through the GL already in the process
//! (the app's: `glXGetProcAddressARB` or `eglGetProcAddress`, found with dlsym) or through the
//! offline context's libEGL. A loader returns an address for any name, also one the context
//! does not support: `Caps::check` (caps.rs) decides from the context's version and extensions
//! before any function past GL 1.x is called. The GL constants the backend uses are here too.

use super::error::GlError;
use std::ffi::{c_void, CStr};

pub type Enum = u32;
pub type Uint = u32;
pub type Int = i32;
pub type Sizei = i32;
pub type IntPtr = isize;
/// A GLsync: an opaque pointer.
pub type Sync = *const c_void;

/// Resolves a GL function name (NUL-terminated) to its address; null where there is none.
pub type ProcLoader<'a> = &'a mut dyn FnMut(&CStr) -> *const c_void;

macro_rules! gl_functions {
    (
        $($field:ident = $name:literal : fn($($arg:ty),*) $(-> $ret:ty)?;)*
        @optional
        $($ofield:ident = $oname:literal : fn($($oarg:ty),*) $(-> $oret:ty)?;)*
    ) => {
        /// The entry points, each a function pointer of the context that was current when
        /// they were loaded (GL function pointers are valid for every context of the same
        /// driver; the backend calls them only with its context current). The optional ones
        /// are the compatibility profile's, called only on such a context (`Caps`).
        pub struct Gl {
            $(pub $field: unsafe extern "system" fn($($arg),*) $(-> $ret)?,)*
            $(pub $ofield: Option<unsafe extern "system" fn($($oarg),*) $(-> $oret)?>,)*
        }

        impl Gl {
            /// Every entry point through `get`; an error naming the first required one it
            /// does not find.
            pub fn load(get: ProcLoader) -> Result<Gl, GlError> {
                Ok(Gl {
                    $($field: {
                        let name = CStr::from_bytes_with_nul(concat!($name, "\0").as_bytes())
                            .expect("a NUL-terminated name");
                        let p = get(name);
                        if p.is_null() {
                            return Err(GlError::MissingFunction($name));
                        }
                        // SAFETY: the loader returned this address for this GL function,
                        // whose C signature is the one declared here.
                        unsafe {
                            std::mem::transmute::<*const c_void, unsafe extern "system" fn($($arg),*) $(-> $ret)?>(p)
                        }
                    },)*
                    $($ofield: {
                        let name = CStr::from_bytes_with_nul(concat!($oname, "\0").as_bytes())
                            .expect("a NUL-terminated name");
                        let p = get(name);
                        // SAFETY: as above, where the loader found one.
                        (!p.is_null()).then(|| unsafe {
                            std::mem::transmute::<*const c_void, unsafe extern "system" fn($($oarg),*) $(-> $oret)?>(p)
                        })
                    },)*
                })
            }
        }
    };
}

gl_functions! {
    get_string = "glGetString": fn(Enum) -> *const u8;
    get_stringi = "glGetStringi": fn(Enum, Uint) -> *const u8;
    get_integerv = "glGetIntegerv": fn(Enum, *mut Int);
    get_integeri_v = "glGetIntegeri_v": fn(Enum, Uint, *mut Int);
    get_integer64i_v = "glGetInteger64i_v": fn(Enum, Uint, *mut i64);
    get_floatv = "glGetFloatv": fn(Enum, *mut f32);
    is_enabled = "glIsEnabled": fn(Enum) -> u8;
    enable = "glEnable": fn(Enum);
    disable = "glDisable": fn(Enum);
    create_shader = "glCreateShader": fn(Enum) -> Uint;
    shader_source = "glShaderSource": fn(Uint, Sizei, *const *const i8, *const Int);
    compile_shader = "glCompileShader": fn(Uint);
    get_shaderiv = "glGetShaderiv": fn(Uint, Enum, *mut Int);
    get_shader_info_log = "glGetShaderInfoLog": fn(Uint, Sizei, *mut Sizei, *mut i8);
    delete_shader = "glDeleteShader": fn(Uint);
    create_program = "glCreateProgram": fn() -> Uint;
    attach_shader = "glAttachShader": fn(Uint, Uint);
    detach_shader = "glDetachShader": fn(Uint, Uint);
    link_program = "glLinkProgram": fn(Uint);
    get_programiv = "glGetProgramiv": fn(Uint, Enum, *mut Int);
    is_texture = "glIsTexture": fn(Uint) -> u8;
    is_buffer = "glIsBuffer": fn(Uint) -> u8;
    is_sampler = "glIsSampler": fn(Uint) -> u8;
    is_program_pipeline = "glIsProgramPipeline": fn(Uint) -> u8;
    get_program_info_log = "glGetProgramInfoLog": fn(Uint, Sizei, *mut Sizei, *mut i8);
    delete_program = "glDeleteProgram": fn(Uint);
    program_parameteri = "glProgramParameteri": fn(Uint, Enum, Int);
    get_program_binary = "glGetProgramBinary": fn(Uint, Sizei, *mut Sizei, *mut Enum, *mut c_void);
    program_binary = "glProgramBinary": fn(Uint, Enum, *const c_void, Sizei);
    get_uniform_location = "glGetUniformLocation": fn(Uint, *const i8) -> Int;
    program_uniform1ui = "glProgramUniform1ui": fn(Uint, Int, Uint);
    program_uniform1f = "glProgramUniform1f": fn(Uint, Int, f32);
    program_uniform2ui = "glProgramUniform2ui": fn(Uint, Int, Uint, Uint);
    program_uniform4f = "glProgramUniform4f": fn(Uint, Int, f32, f32, f32, f32);
    use_program = "glUseProgram": fn(Uint);
    bind_program_pipeline = "glBindProgramPipeline": fn(Uint);
    active_texture = "glActiveTexture": fn(Enum);
    bind_texture = "glBindTexture": fn(Enum, Uint);
    bind_sampler = "glBindSampler": fn(Uint, Uint);
    create_buffers = "glCreateBuffers": fn(Sizei, *mut Uint);
    named_buffer_data = "glNamedBufferData": fn(Uint, IntPtr, *const c_void, Enum);
    named_buffer_sub_data = "glNamedBufferSubData": fn(Uint, IntPtr, IntPtr, *const c_void);
    named_buffer_storage = "glNamedBufferStorage": fn(Uint, IntPtr, *const c_void, u32);
    map_named_buffer_range = "glMapNamedBufferRange": fn(Uint, IntPtr, IntPtr, u32) -> *mut c_void;
    unmap_named_buffer = "glUnmapNamedBuffer": fn(Uint) -> u8;
    fence_sync = "glFenceSync": fn(Enum, u32) -> Sync;
    client_wait_sync = "glClientWaitSync": fn(Sync, u32, u64) -> Enum;
    delete_sync = "glDeleteSync": fn(Sync);
    get_named_buffer_parameteriv = "glGetNamedBufferParameteriv": fn(Uint, Enum, *mut Int);
    delete_buffers = "glDeleteBuffers": fn(Sizei, *const Uint);
    bind_buffer = "glBindBuffer": fn(Enum, Uint);
    bind_buffer_range = "glBindBufferRange": fn(Enum, Uint, Uint, IntPtr, IntPtr);
    bind_buffer_base = "glBindBufferBase": fn(Enum, Uint, Uint);
    create_textures = "glCreateTextures": fn(Enum, Sizei, *mut Uint);
    gen_textures = "glGenTextures": fn(Sizei, *mut Uint);
    copy_image_sub_data = "glCopyImageSubData": fn(Uint, Enum, Int, Int, Int, Int, Uint, Enum, Int, Int, Int, Int, Sizei, Sizei, Sizei);
    gen_queries = "glGenQueries": fn(Sizei, *mut Uint);
    delete_queries = "glDeleteQueries": fn(Sizei, *const Uint);
    begin_query = "glBeginQuery": fn(Enum, Uint);
    end_query = "glEndQuery": fn(Enum);
    get_query_objectui64v = "glGetQueryObjectui64v": fn(Uint, Enum, *mut u64);
    query_counter = "glQueryCounter": fn(Uint, Enum);
    texture_view = "glTextureView": fn(Uint, Enum, Uint, Enum, Uint, Uint, Uint, Uint);
    bind_image_texture = "glBindImageTexture": fn(Uint, Uint, Int, u8, Int, Enum, Enum);
    texture_storage_2d = "glTextureStorage2D": fn(Uint, Sizei, Enum, Sizei, Sizei);
    texture_parameteri = "glTextureParameteri": fn(Uint, Enum, Int);
    texture_storage_3d = "glTextureStorage3D": fn(Uint, Sizei, Enum, Sizei, Sizei, Sizei);
    texture_sub_image_2d = "glTextureSubImage2D": fn(Uint, Int, Int, Int, Sizei, Sizei, Enum, Enum, *const c_void);
    texture_sub_image_3d = "glTextureSubImage3D": fn(Uint, Int, Int, Int, Int, Sizei, Sizei, Sizei, Enum, Enum, *const c_void);
    get_texture_sub_image = "glGetTextureSubImage": fn(Uint, Int, Int, Int, Int, Sizei, Sizei, Sizei, Enum, Enum, Sizei, *mut c_void);
    get_texture_parameteriv = "glGetTextureParameteriv": fn(Uint, Enum, *mut Int);
    get_texture_level_parameteriv = "glGetTextureLevelParameteriv": fn(Uint, Int, Enum, *mut Int);
    delete_textures = "glDeleteTextures": fn(Sizei, *const Uint);
    pixel_storei = "glPixelStorei": fn(Enum, Int);
    dispatch_compute = "glDispatchCompute": fn(Uint, Uint, Uint);
    dispatch_compute_indirect = "glDispatchComputeIndirect": fn(IntPtr);
    memory_barrier = "glMemoryBarrier": fn(u32);
    bind_framebuffer = "glBindFramebuffer": fn(Enum, Uint);
    create_framebuffers = "glCreateFramebuffers": fn(Sizei, *mut Uint);
    named_framebuffer_parameteri = "glNamedFramebufferParameteri": fn(Uint, Enum, Int);
    delete_framebuffers = "glDeleteFramebuffers": fn(Sizei, *const Uint);
    is_framebuffer = "glIsFramebuffer": fn(Uint) -> u8;
    object_label = "glObjectLabel": fn(Enum, Uint, Sizei, *const i8);
    debug_message_insert = "glDebugMessageInsert": fn(Enum, Enum, Uint, Enum, Sizei, *const i8);
    get_object_label = "glGetObjectLabel": fn(Enum, Uint, Sizei, *mut Sizei, *mut i8);
    finish = "glFinish": fn();
    @optional
    // The compatibility profile's pixel transfer and colour matrix (state_guard.rs).
    pixel_transferf = "glPixelTransferf": fn(Enum, f32);
    matrix_mode = "glMatrixMode": fn(Enum);
    load_matrixf = "glLoadMatrixf": fn(*const f32);
}

// Queries.
pub const VENDOR: Enum = 0x1F00;
pub const RENDERER: Enum = 0x1F01;
pub const VERSION: Enum = 0x1F02;
pub const EXTENSIONS: Enum = 0x1F03;
pub const NUM_EXTENSIONS: Enum = 0x821D;
pub const MAJOR_VERSION: Enum = 0x821B;
pub const MINOR_VERSION: Enum = 0x821C;
pub const CONTEXT_PROFILE_MASK: Enum = 0x9126;
pub const CONTEXT_ES_PROFILE_BIT: Int = 0x4;
pub const CONTEXT_COMPATIBILITY_PROFILE_BIT: Int = 0x2;
pub const NUM_PROGRAM_BINARY_FORMATS: Enum = 0x87FE;
pub const PROGRAM_BINARY_FORMATS: Enum = 0x87FF;
pub const MAX_COMPUTE_WORK_GROUP_COUNT: Enum = 0x91BE;

// Shaders and programs.
pub const COMPUTE_SHADER: Enum = 0x91B9;
pub const COMPILE_STATUS: Enum = 0x8B81;
pub const LINK_STATUS: Enum = 0x8B82;
pub const INFO_LOG_LENGTH: Enum = 0x8B84;
pub const COMPLETION_STATUS: Enum = 0x91B1;
pub const PROGRAM_BINARY_RETRIEVABLE_HINT: Enum = 0x8257;
pub const PROGRAM_BINARY_LENGTH: Enum = 0x8741;

// State the guard saves (state_guard.rs).
pub const CURRENT_PROGRAM: Enum = 0x8B8D;
pub const PROGRAM_PIPELINE_BINDING: Enum = 0x825A;
pub const ACTIVE_TEXTURE: Enum = 0x84E0;
pub const TEXTURE0: Enum = 0x84C0;
pub const TEXTURE_BINDING_2D: Enum = 0x8069;
pub const SAMPLER_BINDING: Enum = 0x8919;
pub const SHADER_STORAGE_BUFFER: Enum = 0x90D2;
pub const SHADER_STORAGE_BUFFER_BINDING: Enum = 0x90D3;
pub const SHADER_STORAGE_BUFFER_START: Enum = 0x90D4;
pub const SHADER_STORAGE_BUFFER_SIZE: Enum = 0x90D5;
pub const PIXEL_PACK_BUFFER: Enum = 0x88EB;
pub const PIXEL_UNPACK_BUFFER: Enum = 0x88EC;
pub const PIXEL_PACK_BUFFER_BINDING: Enum = 0x88ED;
pub const PIXEL_UNPACK_BUFFER_BINDING: Enum = 0x88EF;
pub const DISPATCH_INDIRECT_BUFFER: Enum = 0x90EE;
pub const DISPATCH_INDIRECT_BUFFER_BINDING: Enum = 0x90EF;
pub const FRAMEBUFFER: Enum = 0x8D40;
pub const FRAMEBUFFER_DEFAULT_WIDTH: Enum = 0x9310;
pub const FRAMEBUFFER_DEFAULT_HEIGHT: Enum = 0x9311;
pub const DRAW_FRAMEBUFFER: Enum = 0x8CA9;
pub const READ_FRAMEBUFFER: Enum = 0x8CA8;
pub const DRAW_FRAMEBUFFER_BINDING: Enum = 0x8CA6;
pub const READ_FRAMEBUFFER_BINDING: Enum = 0x8CAA;
pub const FRAMEBUFFER_SRGB: Enum = 0x8DB9;
pub const DEBUG_OUTPUT: Enum = 0x92E0;
pub const DEBUG_SOURCE_THIRD_PARTY: Enum = 0x8249;
pub const DEBUG_TYPE_OTHER: Enum = 0x8251;
pub const DEBUG_SEVERITY_MEDIUM: Enum = 0x9147;
pub const PACK_SWAP_BYTES: Enum = 0x0D00;
pub const PACK_LSB_FIRST: Enum = 0x0D01;
pub const PACK_ROW_LENGTH: Enum = 0x0D02;
pub const PACK_SKIP_ROWS: Enum = 0x0D03;
pub const PACK_SKIP_PIXELS: Enum = 0x0D04;
pub const PACK_ALIGNMENT: Enum = 0x0D05;
pub const PACK_SKIP_IMAGES: Enum = 0x806B;
pub const PACK_IMAGE_HEIGHT: Enum = 0x806C;
pub const UNPACK_SWAP_BYTES: Enum = 0x0CF0;
pub const UNPACK_LSB_FIRST: Enum = 0x0CF1;
pub const UNPACK_ROW_LENGTH: Enum = 0x0CF2;
pub const UNPACK_SKIP_ROWS: Enum = 0x0CF3;
pub const UNPACK_SKIP_PIXELS: Enum = 0x0CF4;
pub const UNPACK_ALIGNMENT: Enum = 0x0CF5;
pub const UNPACK_SKIP_IMAGES: Enum = 0x806D;
pub const UNPACK_IMAGE_HEIGHT: Enum = 0x806E;

// The compatibility profile's pixel transfer (glPixelTransfer) and its imaging subset
// (GL_ARB_imaging), which apply to transfers of non-integer texels; the state guard sets them
// to these neutral values around the backend's calls.
pub const PIXEL_TRANSFER_NEUTRAL: [(Enum, f32); 14] = [
    (0x0D10, 0.0), // GL_MAP_COLOR
    (0x0D11, 0.0), // GL_MAP_STENCIL
    (0x0D12, 0.0), // GL_INDEX_SHIFT
    (0x0D13, 0.0), // GL_INDEX_OFFSET
    (0x0D14, 1.0), // GL_RED_SCALE
    (0x0D15, 0.0), // GL_RED_BIAS
    (0x0D18, 1.0), // GL_GREEN_SCALE
    (0x0D19, 0.0), // GL_GREEN_BIAS
    (0x0D1A, 1.0), // GL_BLUE_SCALE
    (0x0D1B, 0.0), // GL_BLUE_BIAS
    (0x0D1C, 1.0), // GL_ALPHA_SCALE
    (0x0D1D, 0.0), // GL_ALPHA_BIAS
    (0x0D1E, 1.0), // GL_DEPTH_SCALE
    (0x0D1F, 0.0), // GL_DEPTH_BIAS
];
pub const IMAGING_TRANSFER_NEUTRAL: [(Enum, f32); 16] = [
    (0x801C, 1.0), // GL_POST_CONVOLUTION_RED_SCALE
    (0x801D, 1.0), // GL_POST_CONVOLUTION_GREEN_SCALE
    (0x801E, 1.0), // GL_POST_CONVOLUTION_BLUE_SCALE
    (0x801F, 1.0), // GL_POST_CONVOLUTION_ALPHA_SCALE
    (0x8020, 0.0), // GL_POST_CONVOLUTION_RED_BIAS
    (0x8021, 0.0), // GL_POST_CONVOLUTION_GREEN_BIAS
    (0x8022, 0.0), // GL_POST_CONVOLUTION_BLUE_BIAS
    (0x8023, 0.0), // GL_POST_CONVOLUTION_ALPHA_BIAS
    (0x80B4, 1.0), // GL_POST_COLOR_MATRIX_RED_SCALE
    (0x80B5, 1.0), // GL_POST_COLOR_MATRIX_GREEN_SCALE
    (0x80B6, 1.0), // GL_POST_COLOR_MATRIX_BLUE_SCALE
    (0x80B7, 1.0), // GL_POST_COLOR_MATRIX_ALPHA_SCALE
    (0x80B8, 0.0), // GL_POST_COLOR_MATRIX_RED_BIAS
    (0x80B9, 0.0), // GL_POST_COLOR_MATRIX_GREEN_BIAS
    (0x80BA, 0.0), // GL_POST_COLOR_MATRIX_BLUE_BIAS
    (0x80BB, 0.0), // GL_POST_COLOR_MATRIX_ALPHA_BIAS
];
/// The imaging subset's stages, each off by default.
pub const IMAGING_STAGES: [Enum; 8] = [
    0x80D0, // GL_COLOR_TABLE
    0x8010, // GL_CONVOLUTION_1D
    0x8011, // GL_CONVOLUTION_2D
    0x8012, // GL_SEPARABLE_2D
    0x80D1, // GL_POST_CONVOLUTION_COLOR_TABLE
    0x80D2, // GL_POST_COLOR_MATRIX_COLOR_TABLE
    0x8024, // GL_HISTOGRAM
    0x802E, // GL_MINMAX
];
pub const COLOR_MATRIX: Enum = 0x80B1;
pub const MATRIX_MODE: Enum = 0x0BA0;
/// glMatrixMode's colour matrix (GL_COLOR).
pub const COLOR: Enum = 0x1800;

// Buffers and textures.
pub const DYNAMIC_COPY: Enum = 0x88EA;
pub const MAP_WRITE_BIT: u32 = 0x0002;
pub const MAP_PERSISTENT_BIT: u32 = 0x0040;
pub const MAP_COHERENT_BIT: u32 = 0x0080;

// Fences.
pub const SYNC_GPU_COMMANDS_COMPLETE: Enum = 0x9117;
pub const SYNC_FLUSH_COMMANDS_BIT: u32 = 0x0001;
pub const ALREADY_SIGNALED: Enum = 0x911A;
pub const CONDITION_SATISFIED: Enum = 0x911C;

pub const BUFFER_SIZE: Enum = 0x8764;
pub const TEXTURE_2D: Enum = 0x0DE1;
pub const TEXTURE_2D_ARRAY: Enum = 0x8C1A;
pub const TEXTURE_MIN_FILTER: Enum = 0x2801;
pub const TEXTURE_MAG_FILTER: Enum = 0x2800;
pub const NEAREST: Int = 0x2600;
pub const TEXTURE_WIDTH: Enum = 0x1000;
pub const RGBA32UI: Enum = 0x8D70;
pub const RGBA_INTEGER: Enum = 0x8D99;
pub const RGBA: Enum = 0x1908;
pub const UNSIGNED_BYTE: Enum = 0x1401;
pub const UNSIGNED_SHORT: Enum = 0x1403;
pub const UNSIGNED_INT: Enum = 0x1405;
pub const HALF_FLOAT: Enum = 0x140B;
pub const UNSIGNED_INT_2_10_10_10_REV: Enum = 0x8368;

// Internal formats of the app's colour textures.
pub const RGBA8: Enum = 0x8058;
pub const SRGB8_ALPHA8: Enum = 0x8C43;
pub const RGBA16: Enum = 0x805B;
pub const RGBA16F: Enum = 0x881A;
pub const RGB10_A2: Enum = 0x8059;
// Image unit formats of the same sizes (GL_RGBA16 and GL_RGB10_A2 are stored through these).
pub const RGBA16UI: Enum = 0x8D76;
pub const R32UI: Enum = 0x8236;

// Barriers.
pub const SHADER_STORAGE_BARRIER_BIT: u32 = 0x2000;
pub const COMMAND_BARRIER_BIT: u32 = 0x40;
pub const PIXEL_BUFFER_BARRIER_BIT: u32 = 0x80;
pub const TEXTURE_UPDATE_BARRIER_BIT: u32 = 0x100;
pub const BUFFER_UPDATE_BARRIER_BIT: u32 = 0x200;
pub const SHADER_IMAGE_ACCESS_BARRIER_BIT: u32 = 0x20;
pub const ALL_BARRIER_BITS: u32 = 0xFFFF_FFFF;

// Object and transform feedback state the state guard checks.
pub const DELETE_STATUS: Enum = 0x8B80;
pub const TRANSFORM_FEEDBACK_ACTIVE: Enum = 0x8E24;
pub const TRANSFORM_FEEDBACK_PAUSED: Enum = 0x8E23;

// Timer queries (GL 3.3).
pub const TIME_ELAPSED: Enum = 0x88BF;
pub const QUERY_RESULT: Enum = 0x8866;
pub const QUERY_RESULT_AVAILABLE: Enum = 0x8867;
pub const TIMESTAMP: Enum = 0x8E28;
// Query buffer objects (GL 4.4): a bound one takes query results instead of the pointer.
pub const QUERY_BUFFER_BINDING: Enum = 0x9193;

// Image units and texture views (GL 4.2, 4.3).
pub const TEXTURE_IMMUTABLE_FORMAT: Enum = 0x912F;
pub const READ_WRITE: Enum = 0x88BA;
pub const IMAGE_BINDING_NAME: Enum = 0x8F3A;
pub const IMAGE_BINDING_LEVEL: Enum = 0x8F3B;
pub const IMAGE_BINDING_LAYERED: Enum = 0x8F3C;
pub const IMAGE_BINDING_LAYER: Enum = 0x8F3D;
pub const IMAGE_BINDING_ACCESS: Enum = 0x8F3E;
pub const IMAGE_BINDING_FORMAT: Enum = 0x906E;
pub const TEXTURE_HEIGHT: Enum = 0x1001;
pub const TEXTURE_DEPTH: Enum = 0x8071;
pub const TEXTURE_INTERNAL_FORMAT: Enum = 0x1003;
pub const TEXTURE_TARGET: Enum = 0x1006;

impl Gl {
    /// The entry points of the GL already loaded into the process (the app's): through
    /// `glXGetProcAddressARB`, else `eglGetProcAddress`, found among the process's global
    /// symbols or, for an app that opened its GL library privately (SDL does), in libGL,
    /// libGLX or libEGL if one is loaded (never loading one).
    pub fn from_process() -> Result<Gl, GlError> {
        type GetProc = unsafe extern "C" fn(*const i8) -> *const c_void;
        let in_handle = |handle: *mut c_void, name: &CStr| {
            // SAFETY: dlsym with RTLD_DEFAULT or a handle dlopen gave, and a NUL-terminated
            // name, only looks a symbol up.
            let p = unsafe { libc::dlsym(handle, name.as_ptr()) };
            // SAFETY: both loaders have this C signature.
            (!p.is_null()).then(|| unsafe { std::mem::transmute::<*mut c_void, GetProc>(p) })
        };
        let loaded = |library: &CStr| {
            // SAFETY: RTLD_NOLOAD returns a handle only to a library already loaded (its
            // reference count raised, never dropped: the app's GL stays for the process).
            let h = unsafe { libc::dlopen(library.as_ptr(), libc::RTLD_NOW | libc::RTLD_NOLOAD) };
            (!h.is_null()).then_some(h)
        };
        let get = in_handle(libc::RTLD_DEFAULT, c"glXGetProcAddressARB")
            .or_else(|| in_handle(libc::RTLD_DEFAULT, c"eglGetProcAddress"))
            .or_else(|| {
                [c"libGL.so.1", c"libGLX.so.0"]
                    .into_iter()
                    .filter_map(loaded)
                    .find_map(|h| in_handle(h, c"glXGetProcAddressARB"))
            })
            .or_else(|| loaded(c"libEGL.so.1").and_then(|h| in_handle(h, c"eglGetProcAddress")))
            .ok_or(GlError::MissingFunction("glXGetProcAddressARB"))?;
        // SAFETY: the loader takes a NUL-terminated name and returns an address or null.
        Gl::load(&mut |name| unsafe { get(name.as_ptr()) })
    }
}
