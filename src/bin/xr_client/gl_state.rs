//! `--check-gl-state` (with `--graphics opengl`): the host's GL state is the host's. Right
//! before each xrEndFrame the client sets non-default values of the GL state that a layer
//! working in the app's context could touch (the current context and drawables, the program and
//! program pipeline, the active texture unit, textures, samplers and image units on unit 0 and
//! every binding number of the layer's shaders, generic and indexed buffer bindings, the pixel
//! store, framebuffers, a few enables, viewport and scissor box) and leaves a GL error pending;
//! after xrEndFrame it reads all of it back, with glGet* and glXGetCurrent* (eglGetCurrent* with
//! --gl-binding egl, its pbuffers EGL surfaces) only, and records
//! every item that changed. Then it puts its own defaults back, so that the next frame's
//! uploads run as without the check.
//!
//! `--disturb-gl-state NAMES` changes the named items after they were set and before
//! xrEndFrame, as a layer that forgets to restore them would: the check must see it.

use crate::error::{fail, Result};
use crate::gl_binding::GlBinding;
use crate::glx::GlContext;
use contrastxr::gpu::core::interface::BINDINGS;
use serde::Serialize;
use std::ffi::{c_char, c_int, c_void};

type Enum = u32;

/// Units checked for textures, samplers and image units, and indices for indexed buffer
/// bindings: 0 up to the highest binding number of the layer's shaders.
const UNITS: usize = {
    let (mut n, mut i) = (1, 0);
    while i < BINDINGS.len() {
        if BINDINGS[i].number as usize + 1 > n {
            n = BINDINGS[i].number as usize + 1;
        }
        i += 1;
    }
    n
};
// GL 4.5's smallest GL_MAX_IMAGE_UNITS and GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS.
const _: () = assert!(UNITS <= 8);

/// The active texture unit the check sets (GL_TEXTURE5).
const ACTIVE_UNIT: u32 = 5;
const _: () = assert!((ACTIVE_UNIT as usize) < UNITS);

const NO_ERROR: Enum = 0;
const INVALID_ENUM: Enum = 0x0500;
/// Not a capability: glEnable raises GL_INVALID_ENUM, the error the client leaves pending.
const NOT_A_CAPABILITY: Enum = 0xFFFF;

const TEXTURE0: Enum = 0x84C0;
const ACTIVE_TEXTURE: Enum = 0x84E0;
const TEXTURE_2D: Enum = 0x0DE1;
const TEXTURE_2D_ARRAY: Enum = 0x8C1A;
const TEXTURE_BINDING_2D: Enum = 0x8069;
const TEXTURE_BINDING_2D_ARRAY: Enum = 0x8C1D;
const SAMPLER_BINDING: Enum = 0x8919;
const CURRENT_PROGRAM: Enum = 0x8B8D;
const PROGRAM_PIPELINE_BINDING: Enum = 0x825A;
const COMPUTE_SHADER: Enum = 0x91B9;
const LINK_STATUS: Enum = 0x8B82;
const RGBA8: Enum = 0x8058;
const R32UI: Enum = 0x8236;
const READ_WRITE: Enum = 0x88BA;
const IMAGE_BINDING_NAME: Enum = 0x8F3A;
const IMAGE_BINDING_LEVEL: Enum = 0x8F3B;
const IMAGE_BINDING_LAYERED: Enum = 0x8F3C;
const IMAGE_BINDING_LAYER: Enum = 0x8F3D;
const IMAGE_BINDING_ACCESS: Enum = 0x8F3E;
const IMAGE_BINDING_FORMAT: Enum = 0x906E;
const SHADER_STORAGE_BUFFER: Enum = 0x90D2;
const SHADER_STORAGE_BUFFER_BINDING: Enum = 0x90D3;
const SHADER_STORAGE_BUFFER_START: Enum = 0x90D4;
const SHADER_STORAGE_BUFFER_SIZE: Enum = 0x90D5;
const SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT: Enum = 0x90DF;
const UNIFORM_BUFFER: Enum = 0x8A11;
const UNIFORM_BUFFER_BINDING: Enum = 0x8A28;
const UNIFORM_BUFFER_START: Enum = 0x8A29;
const UNIFORM_BUFFER_SIZE: Enum = 0x8A2A;
const UNIFORM_BUFFER_OFFSET_ALIGNMENT: Enum = 0x8A34;
const PIXEL_UNPACK_BUFFER: Enum = 0x88EC;
const UNPACK_ALIGNMENT: Enum = 0x0CF5;
const DRAW_FRAMEBUFFER: Enum = 0x8CA9;
const READ_FRAMEBUFFER: Enum = 0x8CA8;
const DRAW_FRAMEBUFFER_BINDING: Enum = 0x8CA6;
const READ_FRAMEBUFFER_BINDING: Enum = 0x8CAA;
const RENDERBUFFER: Enum = 0x8D41;
const RENDERBUFFER_BINDING: Enum = 0x8CA7;
const VERTEX_ARRAY_BINDING: Enum = 0x85B5;
const FRAMEBUFFER_SRGB: Enum = 0x8DB9;
const VIEWPORT: Enum = 0x0BA2;
const SCISSOR_BOX: Enum = 0x0C10;

/// The generic buffer binding points: target, its binding query, the query's name.
const GENERIC_BUFFERS: [(Enum, Enum, &str); 9] = [
    (
        SHADER_STORAGE_BUFFER,
        SHADER_STORAGE_BUFFER_BINDING,
        "GL_SHADER_STORAGE_BUFFER_BINDING",
    ),
    (
        UNIFORM_BUFFER,
        UNIFORM_BUFFER_BINDING,
        "GL_UNIFORM_BUFFER_BINDING",
    ),
    (0x88EB, 0x88ED, "GL_PIXEL_PACK_BUFFER_BINDING"),
    (
        PIXEL_UNPACK_BUFFER,
        0x88EF,
        "GL_PIXEL_UNPACK_BUFFER_BINDING",
    ),
    (0x90EE, 0x90EF, "GL_DISPATCH_INDIRECT_BUFFER_BINDING"),
    (0x8F3F, 0x8F43, "GL_DRAW_INDIRECT_BUFFER_BINDING"),
    (0x8F36, 0x8F36, "GL_COPY_READ_BUFFER_BINDING"),
    (0x8F37, 0x8F37, "GL_COPY_WRITE_BUFFER_BINDING"),
    (0x8892, 0x8894, "GL_ARRAY_BUFFER_BINDING"),
];

/// The pixel store: parameter, its name, the value the check sets, the client's own value
/// (GL's default, but for the alignments: the client's transfers are tightly packed).
const PIXEL_STORE: [(Enum, &str, i32, i32); 16] = [
    (0x0D00, "GL_PACK_SWAP_BYTES", 1, 0),
    (0x0D01, "GL_PACK_LSB_FIRST", 1, 0),
    (0x0D02, "GL_PACK_ROW_LENGTH", 9, 0),
    (0x0D03, "GL_PACK_SKIP_ROWS", 3, 0),
    (0x0D04, "GL_PACK_SKIP_PIXELS", 2, 0),
    (0x0D05, "GL_PACK_ALIGNMENT", 8, 1),
    (0x806B, "GL_PACK_SKIP_IMAGES", 1, 0),
    (0x806C, "GL_PACK_IMAGE_HEIGHT", 5, 0),
    (0x0CF0, "GL_UNPACK_SWAP_BYTES", 1, 0),
    (0x0CF1, "GL_UNPACK_LSB_FIRST", 1, 0),
    (0x0CF2, "GL_UNPACK_ROW_LENGTH", 7, 0),
    (0x0CF3, "GL_UNPACK_SKIP_ROWS", 4, 0),
    (0x0CF4, "GL_UNPACK_SKIP_PIXELS", 3, 0),
    (UNPACK_ALIGNMENT, "GL_UNPACK_ALIGNMENT", 2, 1),
    (0x806D, "GL_UNPACK_SKIP_IMAGES", 2, 0),
    (0x806E, "GL_UNPACK_IMAGE_HEIGHT", 6, 0),
];

/// Capabilities the check enables (the client leaves them disabled).
const ENABLES: [(Enum, &str); 3] = [
    (FRAMEBUFFER_SRGB, "GL_FRAMEBUFFER_SRGB"),
    (0x0C11, "GL_SCISSOR_TEST"),
    (0x0BE2, "GL_BLEND"),
];

/// The viewport and scissor box the check sets (the client's are its 16x16 pbuffer's).
const VIEWPORT_SET: [i32; 4] = [1, 2, 11, 13];
const SCISSOR_SET: [i32; 4] = [3, 4, 5, 6];
const PBUFFER_RECT: [i32; 4] = [0, 0, 16, 16];

/// What --disturb-gl-state can change (each an item's name, without its unit).
pub const DISTURBABLE: [&str; 10] = [
    "glXGetCurrentDrawable",
    "glGetError",
    "GL_ACTIVE_TEXTURE",
    "GL_CURRENT_PROGRAM",
    "GL_TEXTURE_BINDING_2D",
    "GL_IMAGE_BINDING_NAME",
    "GL_PIXEL_UNPACK_BUFFER_BINDING",
    "GL_UNPACK_ALIGNMENT",
    "GL_DRAW_FRAMEBUFFER_BINDING",
    "GL_FRAMEBUFFER_SRGB",
];

/// One item that xrEndFrame changed.
#[derive(Serialize, Debug, Clone, PartialEq)]
pub struct Change {
    /// The xrEndFrame call's index in the run (frames ended before it).
    pub frame: u32,
    /// The query, with the unit or index in brackets: `GL_TEXTURE_BINDING_2D[5]`.
    pub what: String,
    /// A number, or an array for a query of several values.
    pub before: serde_json::Value,
    pub after: serde_json::Value,
}

/// How an item is read back.
#[derive(Clone, Copy, Debug)]
enum Query {
    /// glGetInteger64v (up to 4 values).
    Integer(Enum),
    /// glGetInteger64i_v.
    Indexed(Enum, u32),
    /// glIsEnabled.
    Enabled(Enum),
    Context,
    Drawable,
    ReadDrawable,
}

/// One piece of state, and the value the check sets it to.
struct Item {
    what: String,
    query: Query,
    set: Vec<i64>,
}

type Create = unsafe extern "C" fn(i32, *mut u32);

/// The GL and GLX functions the check calls.
struct Fns {
    get_integer64v: unsafe extern "C" fn(Enum, *mut i64),
    get_integer64i_v: unsafe extern "C" fn(Enum, u32, *mut i64),
    is_enabled: unsafe extern "C" fn(Enum) -> u8,
    enable: unsafe extern "C" fn(Enum),
    disable: unsafe extern "C" fn(Enum),
    get_error: unsafe extern "C" fn() -> Enum,
    active_texture: unsafe extern "C" fn(Enum),
    bind_texture: unsafe extern "C" fn(Enum, u32),
    bind_textures: unsafe extern "C" fn(u32, i32, *const u32),
    bind_samplers: unsafe extern "C" fn(u32, i32, *const u32),
    bind_image_texture: unsafe extern "C" fn(u32, u32, i32, u8, i32, Enum, Enum),
    bind_image_textures: unsafe extern "C" fn(u32, i32, *const u32),
    bind_buffer: unsafe extern "C" fn(Enum, u32),
    bind_buffer_range: unsafe extern "C" fn(Enum, u32, u32, isize, isize),
    bind_buffers_base: unsafe extern "C" fn(Enum, u32, i32, *const u32),
    bind_framebuffer: unsafe extern "C" fn(Enum, u32),
    bind_renderbuffer: unsafe extern "C" fn(Enum, u32),
    bind_vertex_array: unsafe extern "C" fn(u32),
    use_program: unsafe extern "C" fn(u32),
    bind_program_pipeline: unsafe extern "C" fn(u32),
    pixel_store_i: unsafe extern "C" fn(Enum, i32),
    viewport: unsafe extern "C" fn(i32, i32, i32, i32),
    scissor: unsafe extern "C" fn(i32, i32, i32, i32),
    create_textures: unsafe extern "C" fn(Enum, i32, *mut u32),
    texture_storage_2d: unsafe extern "C" fn(u32, i32, Enum, i32, i32),
    texture_storage_3d: unsafe extern "C" fn(u32, i32, Enum, i32, i32, i32),
    create_samplers: Create,
    create_buffers: Create,
    named_buffer_storage: unsafe extern "C" fn(u32, isize, *const c_void, u32),
    create_framebuffers: Create,
    create_renderbuffers: Create,
    create_vertex_arrays: Create,
    create_program_pipelines: Create,
    create_shader_program_v: unsafe extern "C" fn(Enum, i32, *const *const c_char) -> u32,
    get_program_iv: unsafe extern "C" fn(u32, Enum, *mut i32),
    window_system: WindowSystem,
}

/// The window-system calls of the check: GLX's, or with --gl-binding egl EGL's (whose draw and
/// read surfaces stand for GLX's drawables, held as u64 as XIDs are).
enum WindowSystem {
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
    fn load(gl: &GlContext) -> Result<WindowSystem> {
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
    fn names(&self) -> [&'static str; GLX_ITEMS] {
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
    unsafe fn current_context(&self) -> *mut c_void {
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
    unsafe fn current_drawable(&self, read: bool) -> u64 {
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
    unsafe fn make_current(
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
    fn load(gl: &GlContext) -> Result<Fns> {
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

/// The objects whose names the check binds; created once, never deleted (the run is short).
struct Objects {
    program: u32,
    pipeline: u32,
    textures_2d: [u32; UNITS],
    textures_array: [u32; UNITS],
    samplers: [u32; UNITS],
    storage: [u32; UNITS],
    uniform: [u32; UNITS],
    generic: [u32; GENERIC_BUFFERS.len()],
    storage_alignment: i64,
    uniform_alignment: i64,
    /// Draw and read.
    framebuffers: [u32; 2],
    renderbuffer: u32,
    vertex_array: u32,
    /// Two pbuffers of the check's own: the draw and read drawables it makes current.
    draw: u64,
    read: u64,
}

/// Bytes of each buffer; the indexed ranges lie inside it at every offset alignment up to 256.
const BUFFER_BYTES: isize = 4096;

impl Objects {
    fn create(f: &Fns, gl: &GlContext) -> Result<Objects> {
        let names = |create: Create, n: usize| {
            let mut v = vec![0u32; n];
            // SAFETY: room for n names.
            unsafe { create(n as i32, v.as_mut_ptr()) };
            v
        };
        let array = |v: Vec<u32>| -> [u32; UNITS] { v.try_into().expect("UNITS names") };
        let source = c"#version 430 core\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
        let mut linked = 0;
        // SAFETY: one NUL-terminated source; the program is a name of this context.
        let program = unsafe {
            let program = (f.create_shader_program_v)(COMPUTE_SHADER, 1, &source.as_ptr());
            (f.get_program_iv)(program, LINK_STATUS, &mut linked);
            program
        };
        if program == 0 || linked == 0 {
            return fail("--check-gl-state: the compute program does not link");
        }
        let mut textures_2d = [0; UNITS];
        let mut textures_array = [0; UNITS];
        // SAFETY: room for UNITS names; storage of two levels of 4x4 (x2 layers) RGBA8 on
        // textures just created.
        unsafe {
            (f.create_textures)(TEXTURE_2D, UNITS as i32, textures_2d.as_mut_ptr());
            (f.create_textures)(TEXTURE_2D_ARRAY, UNITS as i32, textures_array.as_mut_ptr());
            for t in textures_2d {
                (f.texture_storage_2d)(t, 2, RGBA8, 4, 4);
            }
            for t in textures_array {
                (f.texture_storage_3d)(t, 2, RGBA8, 4, 4, 2);
            }
        }
        let buffers = names(f.create_buffers, 2 * UNITS + GENERIC_BUFFERS.len());
        for &b in &buffers {
            // SAFETY: a buffer just created, immutable storage with no data and no flags.
            unsafe { (f.named_buffer_storage)(b, BUFFER_BYTES, std::ptr::null(), 0) };
        }
        let alignment = |pname| {
            let mut v = 0;
            // SAFETY: a single-valued query.
            unsafe { (f.get_integer64v)(pname, &mut v) };
            v.max(1)
        };
        let framebuffers = names(f.create_framebuffers, 2);
        let objects = Objects {
            program,
            pipeline: names(f.create_program_pipelines, 1)[0],
            textures_2d,
            textures_array,
            samplers: array(names(f.create_samplers, UNITS)),
            storage: array(buffers[..UNITS].to_vec()),
            uniform: array(buffers[UNITS..2 * UNITS].to_vec()),
            generic: buffers[2 * UNITS..].try_into().expect("one per target"),
            storage_alignment: alignment(SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT),
            uniform_alignment: alignment(UNIFORM_BUFFER_OFFSET_ALIGNMENT),
            framebuffers: [framebuffers[0], framebuffers[1]],
            renderbuffer: names(f.create_renderbuffers, 1)[0],
            vertex_array: names(f.create_vertex_arrays, 1)[0],
            draw: pbuffer(gl)?,
            read: pbuffer(gl)?,
        };
        if objects.storage_alignment > 256 || objects.uniform_alignment > 256 {
            return fail("--check-gl-state: buffer offset alignments above 256");
        }
        Ok(objects)
    }

    /// Indexed range `i` of a buffer target: (offset, size).
    fn range(alignment: i64, i: usize) -> (i64, i64) {
        (alignment * (i as i64 + 1), 16 * (i as i64 + 1))
    }
}

/// The check over a run: its objects, and what it found.
pub struct GlStateCheck {
    f: Fns,
    objects: Objects,
    items: Vec<Item>,
    /// Every item as the client keeps it between checks (read once at the start).
    defaults: Vec<Vec<i64>>,
    display: *mut c_void,
    context: *mut c_void,
    drawable: u64,
    /// The read drawable of this check: every second check reads where it draws, as most
    /// apps do, the others from a pbuffer of their own.
    read_drawable: u64,
    disturb: Vec<String>,
    /// The frame of the set state, between `before_end_frame` and `after_end_frame`.
    frame: Option<u32>,
    pub checked: u32,
    pub changed: Vec<Change>,
}

fn json(v: &[i64]) -> serde_json::Value {
    match v {
        [one] => (*one).into(),
        many => many.into(),
    }
}

impl GlStateCheck {
    /// Creates the check's objects in `gl`'s context (current on this thread) and reads the
    /// client's own state; `disturb`: the names of DISTURBABLE to change before xrEndFrame.
    pub fn new(gl: &GlContext, disturb: &[String]) -> Result<GlStateCheck> {
        if let Some(bad) = disturb.iter().find(|d| !DISTURBABLE.contains(&d.as_str())) {
            return fail(format!(
                "--disturb-gl-state: unknown item {bad}, use some of {}",
                DISTURBABLE.join(",")
            ));
        }
        let f = Fns::load(gl)?;
        let objects = Objects::create(&f, gl)?;
        let mut check = GlStateCheck {
            items: items(&objects, gl.context, f.window_system.names()),
            f,
            objects,
            defaults: Vec::new(),
            display: gl.display,
            context: gl.context,
            drawable: gl.drawable,
            read_drawable: 0,
            disturb: disturb.to_vec(),
            frame: None,
            checked: 0,
            changed: Vec::new(),
        };
        check.gl_error("creating the check's objects")?;
        check.defaults = check.read_all();
        check.gl_error("reading the client's GL state")?;
        let same: Vec<_> = check
            .items
            .iter()
            .zip(&check.defaults)
            // The context is the client's one: the check makes it current on other drawables.
            .enumerate()
            .filter(|&(i, (item, default))| item.set == *default && i != CONTEXT_ITEM)
            .map(|(_, pair)| pair)
            .map(|(item, _)| item.what.as_str())
            .collect();
        if !same.is_empty() {
            return fail(format!(
                "--check-gl-state would set the client's own values of {}",
                same.join(" ")
            ));
        }
        Ok(check)
    }

    /// Sets the state (after the frame's rendering), reads it back, leaves GL_INVALID_ENUM
    /// pending, and disturbs what --disturb-gl-state names. `frame`: frames ended before.
    pub fn before_end_frame(&mut self, frame: u32) -> Result<()> {
        let o = &self.objects;
        self.read_drawable = if self.checked % 2 == 0 {
            o.read
        } else {
            o.draw
        };
        self.items[READ_DRAWABLE_ITEM].set = vec![self.read_drawable as i64];
        self.set();
        self.gl_error("setting the GL state")?;
        let before = self.read_all();
        self.gl_error("reading the GL state back")?;
        for (item, got) in self.items.iter().zip(&before) {
            if item.set != *got {
                return fail(format!(
                    "--check-gl-state set {} to {:?} but reads {got:?}",
                    item.what, item.set
                ));
            }
        }
        // SAFETY: the context is current; an invalid capability only raises the error.
        unsafe { (self.f.enable)(NOT_A_CAPABILITY) };
        self.disturb();
        self.frame = Some(frame);
        Ok(())
    }

    /// Reads everything back after xrEndFrame, records what changed, and puts the client's
    /// own state back.
    pub fn after_end_frame(&mut self) -> Result<()> {
        let Some(frame) = self.frame.take() else {
            return Ok(());
        };
        let mut changed = Vec::new();
        let mut note = |what: &str, before: &[i64], after: &[i64]| {
            if before != after {
                changed.push(Change {
                    frame,
                    what: what.to_string(),
                    before: json(before),
                    after: json(after),
                });
            }
        };
        // The current context and drawables first: GLX queries, no GL call before them.
        let (glx, gl_items) = self.items.split_at(GLX_ITEMS);
        for item in glx {
            note(&item.what, &item.set, &self.read(item));
        }
        // SAFETY: a GLX query of this thread's current context.
        if unsafe { self.f.window_system.current_context() } != self.context {
            // The rest is the client's context's state: read it there.
            // SAFETY: the client's own display, context and pbuffers.
            unsafe {
                self.f.window_system.make_current(
                    self.display,
                    self.objects.draw,
                    self.read_drawable,
                    self.context,
                )
            };
        }
        // SAFETY: the context is current; glGetError reads (and clears) the error flags.
        let errors = unsafe { [(self.f.get_error)(), (self.f.get_error)()] };
        note("glGetError", &[INVALID_ENUM as i64], &[errors[0] as i64]);
        note("glGetError (then)", &[NO_ERROR as i64], &[errors[1] as i64]);
        for item in gl_items {
            note(&item.what, &item.set, &self.read(item));
        }
        self.changed.extend(changed);
        self.checked += 1;
        self.gl_error("reading the GL state after xrEndFrame")?;
        self.restore();
        self.gl_error("putting the client's GL state back")?;
        let now = self.read_all();
        if let Some((item, _)) = self
            .items
            .iter()
            .zip(now.iter().zip(&self.defaults))
            .find(|(_, (now, default))| now != default)
        {
            return fail(format!("--check-gl-state could not put {} back", item.what));
        }
        Ok(())
    }

    fn gl_error(&self, doing: &str) -> Result<()> {
        // SAFETY: the context is current.
        match unsafe { (self.f.get_error)() } {
            NO_ERROR => Ok(()),
            e => fail(format!("--check-gl-state: GL error 0x{e:04x} {doing}")),
        }
    }

    fn read_all(&self) -> Vec<Vec<i64>> {
        self.items.iter().map(|item| self.read(item)).collect()
    }

    fn read(&self, item: &Item) -> Vec<i64> {
        let f = &self.f;
        let mut v = [0i64; 4];
        // SAFETY: queries of valid names (units and indices below GL 4.5's minimums) into room
        // for 4 values, the most any of them returns.
        unsafe {
            match item.query {
                Query::Integer(pname) => (f.get_integer64v)(pname, v.as_mut_ptr()),
                Query::Indexed(pname, i) => (f.get_integer64i_v)(pname, i, v.as_mut_ptr()),
                Query::Enabled(cap) => v[0] = (f.is_enabled)(cap) as i64,
                Query::Context => v[0] = f.window_system.current_context() as i64,
                Query::Drawable => v[0] = f.window_system.current_drawable(false) as i64,
                Query::ReadDrawable => v[0] = f.window_system.current_drawable(true) as i64,
            }
        }
        v[..item.set.len()].to_vec()
    }

    fn set(&self) {
        let (f, o) = (&self.f, &self.objects);
        // SAFETY: the client's context and pbuffers; names this check created, units and
        // indices below GL 4.5's minimums, ranges inside the buffers at aligned offsets. The
        // generic buffer bindings come after the indexed ones, which set them too.
        unsafe {
            let ws = &f.window_system;
            ws.make_current(self.display, o.draw, self.read_drawable, self.context);
            (f.use_program)(o.program);
            (f.bind_program_pipeline)(o.pipeline);
            for unit in 0..UNITS {
                (f.active_texture)(TEXTURE0 + unit as Enum);
                (f.bind_texture)(TEXTURE_2D, o.textures_2d[unit]);
                (f.bind_texture)(TEXTURE_2D_ARRAY, o.textures_array[unit]);
            }
            (f.active_texture)(TEXTURE0 + ACTIVE_UNIT);
            (f.bind_samplers)(0, UNITS as i32, o.samplers.as_ptr());
            for unit in 0..UNITS {
                (f.bind_image_texture)(
                    unit as u32,
                    o.textures_array[unit],
                    1,
                    1,
                    1,
                    READ_WRITE,
                    R32UI,
                );
            }
            for i in 0..UNITS {
                let (offset, size) = Objects::range(o.storage_alignment, i);
                let (target, buffer) = (SHADER_STORAGE_BUFFER, o.storage[i]);
                (f.bind_buffer_range)(target, i as u32, buffer, offset as isize, size as isize);
                let (offset, size) = Objects::range(o.uniform_alignment, i);
                let (target, buffer) = (UNIFORM_BUFFER, o.uniform[i]);
                (f.bind_buffer_range)(target, i as u32, buffer, offset as isize, size as isize);
            }
            for ((target, _, _), buffer) in GENERIC_BUFFERS.iter().zip(o.generic) {
                (f.bind_buffer)(*target, buffer);
            }
            for (pname, _, value, _) in PIXEL_STORE {
                (f.pixel_store_i)(pname, value);
            }
            (f.bind_framebuffer)(DRAW_FRAMEBUFFER, o.framebuffers[0]);
            (f.bind_framebuffer)(READ_FRAMEBUFFER, o.framebuffers[1]);
            (f.bind_renderbuffer)(RENDERBUFFER, o.renderbuffer);
            (f.bind_vertex_array)(o.vertex_array);
            for (cap, _) in ENABLES {
                (f.enable)(cap);
            }
            let [x, y, w, h] = VIEWPORT_SET;
            (f.viewport)(x, y, w, h);
            let [x, y, w, h] = SCISSOR_SET;
            (f.scissor)(x, y, w, h);
        }
    }

    /// The client's own state: its pbuffer current, nothing bound, its pixel store.
    fn restore(&self) {
        let f = &self.f;
        let none = std::ptr::null();
        // SAFETY: the client's context and pbuffer; unbinding with null name lists (the
        // multi-bind calls) and zero names; valid pixel store values.
        unsafe {
            let ws = &f.window_system;
            ws.make_current(self.display, self.drawable, self.drawable, self.context);
            (f.use_program)(0);
            (f.bind_program_pipeline)(0);
            (f.bind_textures)(0, UNITS as i32, none);
            (f.active_texture)(TEXTURE0);
            (f.bind_samplers)(0, UNITS as i32, none);
            (f.bind_image_textures)(0, UNITS as i32, none);
            (f.bind_buffers_base)(SHADER_STORAGE_BUFFER, 0, UNITS as i32, none);
            (f.bind_buffers_base)(UNIFORM_BUFFER, 0, UNITS as i32, none);
            for (target, _, _) in GENERIC_BUFFERS {
                (f.bind_buffer)(target, 0);
            }
            for (pname, _, _, value) in PIXEL_STORE {
                (f.pixel_store_i)(pname, value);
            }
            (f.bind_framebuffer)(DRAW_FRAMEBUFFER, 0);
            (f.bind_framebuffer)(READ_FRAMEBUFFER, 0);
            (f.bind_renderbuffer)(RENDERBUFFER, 0);
            (f.bind_vertex_array)(0);
            for (cap, _) in ENABLES {
                (f.disable)(cap);
            }
            let [x, y, w, h] = PBUFFER_RECT;
            (f.viewport)(x, y, w, h);
            (f.scissor)(x, y, w, h);
        }
    }

    /// What a layer that forgets to restore would leave: each item of --disturb-gl-state
    /// changed to another value.
    fn disturb(&self) {
        let (f, o) = (&self.f, &self.objects);
        for name in &self.disturb {
            // SAFETY: as in `set`: the client's own objects, pbuffers and valid values.
            unsafe {
                match name.as_str() {
                    "glXGetCurrentDrawable" => {
                        f.window_system.make_current(
                            self.display,
                            self.drawable,
                            self.read_drawable,
                            self.context,
                        );
                    }
                    "glGetError" => {
                        (f.get_error)();
                    }
                    "GL_ACTIVE_TEXTURE" => (f.active_texture)(TEXTURE0),
                    "GL_CURRENT_PROGRAM" => (f.use_program)(0),
                    "GL_TEXTURE_BINDING_2D" => (f.bind_textures)(ACTIVE_UNIT, 1, &o.textures_2d[0]),
                    "GL_IMAGE_BINDING_NAME" => {
                        (f.bind_image_texture)(0, o.textures_array[1], 1, 1, 1, READ_WRITE, R32UI)
                    }
                    "GL_PIXEL_UNPACK_BUFFER_BINDING" => (f.bind_buffer)(PIXEL_UNPACK_BUFFER, 0),
                    "GL_UNPACK_ALIGNMENT" => (f.pixel_store_i)(UNPACK_ALIGNMENT, 4),
                    "GL_DRAW_FRAMEBUFFER_BINDING" => (f.bind_framebuffer)(DRAW_FRAMEBUFFER, 0),
                    "GL_FRAMEBUFFER_SRGB" => (f.disable)(FRAMEBUFFER_SRGB),
                    _ => unreachable!("checked in new"),
                }
            }
        }
    }
}

/// The first items: the current context, draw and read drawables.
const GLX_ITEMS: usize = 3;
const CONTEXT_ITEM: usize = 0;
const READ_DRAWABLE_ITEM: usize = 2;

/// Every item, with the value `set` gives it (the GLX_ITEMS first).
fn items(o: &Objects, context: *mut c_void, names: [&str; GLX_ITEMS]) -> Vec<Item> {
    let item = |what: String, query, set: &[i64]| Item {
        what,
        query,
        set: set.to_vec(),
    };
    let name = |n: u32| [n as i64];
    let mut items = vec![
        item(names[0].into(), Query::Context, &[context as i64]),
        item(names[1].into(), Query::Drawable, &[o.draw as i64]),
        item(names[2].into(), Query::ReadDrawable, &[o.read as i64]),
        item(
            "GL_CURRENT_PROGRAM".into(),
            Query::Integer(CURRENT_PROGRAM),
            &name(o.program),
        ),
        item(
            "GL_PROGRAM_PIPELINE_BINDING".into(),
            Query::Integer(PROGRAM_PIPELINE_BINDING),
            &name(o.pipeline),
        ),
        item(
            "GL_ACTIVE_TEXTURE".into(),
            Query::Integer(ACTIVE_TEXTURE),
            &name(TEXTURE0 + ACTIVE_UNIT),
        ),
    ];
    for unit in 0..UNITS {
        let u = unit as u32;
        let at = |what: &str| format!("{what}[{unit}]");
        items.extend([
            item(
                at("GL_TEXTURE_BINDING_2D"),
                Query::Indexed(TEXTURE_BINDING_2D, u),
                &name(o.textures_2d[unit]),
            ),
            item(
                at("GL_TEXTURE_BINDING_2D_ARRAY"),
                Query::Indexed(TEXTURE_BINDING_2D_ARRAY, u),
                &name(o.textures_array[unit]),
            ),
            item(
                at("GL_SAMPLER_BINDING"),
                Query::Indexed(SAMPLER_BINDING, u),
                &name(o.samplers[unit]),
            ),
            item(
                at("GL_IMAGE_BINDING_NAME"),
                Query::Indexed(IMAGE_BINDING_NAME, u),
                &name(o.textures_array[unit]),
            ),
            item(
                at("GL_IMAGE_BINDING_LEVEL"),
                Query::Indexed(IMAGE_BINDING_LEVEL, u),
                &[1],
            ),
            item(
                at("GL_IMAGE_BINDING_LAYERED"),
                Query::Indexed(IMAGE_BINDING_LAYERED, u),
                &[1],
            ),
            item(
                at("GL_IMAGE_BINDING_LAYER"),
                Query::Indexed(IMAGE_BINDING_LAYER, u),
                &[1],
            ),
            item(
                at("GL_IMAGE_BINDING_ACCESS"),
                Query::Indexed(IMAGE_BINDING_ACCESS, u),
                &name(READ_WRITE),
            ),
            item(
                at("GL_IMAGE_BINDING_FORMAT"),
                Query::Indexed(IMAGE_BINDING_FORMAT, u),
                &name(R32UI),
            ),
        ]);
        let indexed = [
            (
                "GL_SHADER_STORAGE_BUFFER",
                [
                    SHADER_STORAGE_BUFFER_BINDING,
                    SHADER_STORAGE_BUFFER_START,
                    SHADER_STORAGE_BUFFER_SIZE,
                ],
                o.storage[unit],
                o.storage_alignment,
            ),
            (
                "GL_UNIFORM_BUFFER",
                [
                    UNIFORM_BUFFER_BINDING,
                    UNIFORM_BUFFER_START,
                    UNIFORM_BUFFER_SIZE,
                ],
                o.uniform[unit],
                o.uniform_alignment,
            ),
        ];
        for (target, [binding, start, size], buffer, alignment) in indexed {
            let (offset, bytes) = Objects::range(alignment, unit);
            items.extend([
                item(
                    at(&format!("{target}_BINDING")),
                    Query::Indexed(binding, u),
                    &name(buffer),
                ),
                item(
                    at(&format!("{target}_START")),
                    Query::Indexed(start, u),
                    &[offset],
                ),
                item(
                    at(&format!("{target}_SIZE")),
                    Query::Indexed(size, u),
                    &[bytes],
                ),
            ]);
        }
    }
    for ((_, binding, what), buffer) in GENERIC_BUFFERS.iter().zip(o.generic) {
        items.push(item(
            what.to_string(),
            Query::Integer(*binding),
            &name(buffer),
        ));
    }
    for (pname, what, value, _) in PIXEL_STORE {
        items.push(item(what.into(), Query::Integer(pname), &[value as i64]));
    }
    items.extend([
        item(
            "GL_DRAW_FRAMEBUFFER_BINDING".into(),
            Query::Integer(DRAW_FRAMEBUFFER_BINDING),
            &name(o.framebuffers[0]),
        ),
        item(
            "GL_READ_FRAMEBUFFER_BINDING".into(),
            Query::Integer(READ_FRAMEBUFFER_BINDING),
            &name(o.framebuffers[1]),
        ),
        item(
            "GL_RENDERBUFFER_BINDING".into(),
            Query::Integer(RENDERBUFFER_BINDING),
            &name(o.renderbuffer),
        ),
        item(
            "GL_VERTEX_ARRAY_BINDING".into(),
            Query::Integer(VERTEX_ARRAY_BINDING),
            &name(o.vertex_array),
        ),
    ]);
    for (cap, what) in ENABLES {
        items.push(item(what.into(), Query::Enabled(cap), &[1]));
    }
    let rect = |r: [i32; 4]| r.map(i64::from);
    items.push(item(
        "GL_VIEWPORT".into(),
        Query::Integer(VIEWPORT),
        &rect(VIEWPORT_SET),
    ));
    items.push(item(
        "GL_SCISSOR_BOX".into(),
        Query::Integer(SCISSOR_BOX),
        &rect(SCISSOR_SET),
    ));
    items
}

/// Another 16x16 pbuffer on the context's configuration: a GLX pbuffer, or with EGL an
/// EGLSurface (as u64).
fn pbuffer(gl: &GlContext) -> Result<u64> {
    match gl.binding {
        GlBinding::Xlib => gl.glx_pbuffer(),
        GlBinding::Egl => crate::egl::pbuffer(gl),
    }
}
