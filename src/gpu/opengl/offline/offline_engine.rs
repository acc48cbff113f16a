//! An OpenGL context of the engine's own, for the command-line tool and the tests only (the
//! layer runs on the app's context): EGL on Mesa's surfaceless platform, so no window system is
//! needed, OpenGL 4.5 core, current on the thread that made it. Views are textures made here,
//! their rows stored bottom first as an OpenXR runtime's OpenGL swapchain images are.

use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::params::Params;
use crate::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use crate::gpu::core::blurred_texels::{BlurTaps, BlurredTexels};
use crate::gpu::core::{OfflineBackend, PixelFormat};
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;
use crate::gpu::opengl::frame::{GlFrameRunner, Outcome};
use crate::gpu::opengl::frame::{GlTarget, GlView};
use crate::image::RgbaImage;
use std::ffi::{c_void, CStr};

type EglGetProcAddress = unsafe extern "C" fn(*const i8) -> *const c_void;
type EglGetPlatformDisplay = unsafe extern "C" fn(u32, *mut c_void, *const i32) -> *mut c_void;
type EglInitialize = unsafe extern "C" fn(*mut c_void, *mut i32, *mut i32) -> u32;
type EglBindApi = unsafe extern "C" fn(u32) -> u32;
type EglCreateContext =
    unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *const i32) -> *mut c_void;
type EglMakeCurrent =
    unsafe extern "C" fn(*mut c_void, *mut c_void, *mut c_void, *mut c_void) -> u32;
type EglDestroyContext = unsafe extern "C" fn(*mut c_void, *mut c_void) -> u32;

const PLATFORM_SURFACELESS_MESA: u32 = 0x31DD;
const OPENGL_API: u32 = 0x30A2;
const CONTEXT_MAJOR_VERSION: i32 = 0x3098;
const CONTEXT_MINOR_VERSION: i32 = 0x30FB;
const CONTEXT_OPENGL_PROFILE_MASK: i32 = 0x30FD;
const CONTEXT_OPENGL_CORE_PROFILE_BIT: i32 = 1;
const CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT: i32 = 2;
const NONE: i32 = 0x3038;

/// libEGL's entry points the offline context uses.
struct Egl {
    get_proc_address: EglGetProcAddress,
    make_current: EglMakeCurrent,
    destroy_context: EglDestroyContext,
}

/// The engine on its own surfaceless EGL context (not Send: the context is current on the
/// thread that made it).
pub struct GlOffline {
    engine: GlFrameRunner,
    egl: Egl,
    display: *mut c_void,
    context: *mut c_void,
}

fn egl_symbol(lib: *mut c_void, name: &CStr) -> Result<*mut c_void, GlError> {
    // SAFETY: `lib` is a handle dlopen returned; the name is NUL-terminated.
    let p = unsafe { libc::dlsym(lib, name.as_ptr()) };
    if p.is_null() {
        return Err(GlError::Context(format!(
            "libEGL.so.1 has no {}",
            name.to_string_lossy()
        )));
    }
    Ok(p)
}

impl GlOffline {
    /// An OpenGL 4.5 core context on EGL's surfaceless platform (libEGL.so.1 with Mesa's
    /// EGL_MESA_platform_surfaceless; Debian: libegl1, libegl-mesa0, libgl1-mesa-dri), current
    /// on this thread, and the engine on it.
    pub fn new() -> Result<GlOffline, GlError> {
        Self::with_version((4, 5))
    }

    /// The same with a core context of another version (a test asks for an older one, which
    /// the engine must refuse).
    pub fn with_version(version: (i32, i32)) -> Result<GlOffline, GlError> {
        Self::with_profile(version, false)
    }

    /// An OpenGL 4.5 compatibility-profile context, as many apps make.
    pub fn compatibility() -> Result<GlOffline, GlError> {
        Self::with_profile((4, 5), true)
    }

    fn with_profile((major, minor): (i32, i32), compatibility: bool) -> Result<GlOffline, GlError> {
        // SAFETY: dlopen of a library name; the handle is kept for the process (never closed).
        let lib =
            unsafe { libc::dlopen(c"libEGL.so.1".as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        if lib.is_null() {
            return Err(GlError::Context(
                "libEGL.so.1 is not installed (Debian: apt install libegl1 libegl-mesa0 libgl1-mesa-dri)".into(),
            ));
        }
        // SAFETY: each symbol is libEGL's function of the C signature it is cast to.
        let egl = unsafe {
            Egl {
                get_proc_address: std::mem::transmute::<*mut c_void, EglGetProcAddress>(
                    egl_symbol(lib, c"eglGetProcAddress")?,
                ),
                make_current: std::mem::transmute::<*mut c_void, EglMakeCurrent>(egl_symbol(
                    lib,
                    c"eglMakeCurrent",
                )?),
                destroy_context: std::mem::transmute::<*mut c_void, EglDestroyContext>(egl_symbol(
                    lib,
                    c"eglDestroyContext",
                )?),
            }
        };
        // SAFETY: as above.
        let (initialize, bind_api, create_context) = unsafe {
            (
                std::mem::transmute::<*mut c_void, EglInitialize>(egl_symbol(
                    lib,
                    c"eglInitialize",
                )?),
                std::mem::transmute::<*mut c_void, EglBindApi>(egl_symbol(lib, c"eglBindAPI")?),
                std::mem::transmute::<*mut c_void, EglCreateContext>(egl_symbol(
                    lib,
                    c"eglCreateContext",
                )?),
            )
        };
        // SAFETY: a client extension function looked up by its NUL-terminated name.
        let platform = unsafe { (egl.get_proc_address)(c"eglGetPlatformDisplayEXT".as_ptr()) };
        if platform.is_null() {
            return Err(GlError::Context(
                "EGL has no eglGetPlatformDisplayEXT".into(),
            ));
        }
        // SAFETY: eglGetPlatformDisplayEXT's signature.
        let platform =
            unsafe { std::mem::transmute::<*const c_void, EglGetPlatformDisplay>(platform) };
        // SAFETY: the surfaceless platform takes no native display and no attributes.
        let display = unsafe {
            platform(
                PLATFORM_SURFACELESS_MESA,
                std::ptr::null_mut(),
                std::ptr::null(),
            )
        };
        let (mut egl_major, mut egl_minor) = (0, 0);
        // SAFETY: a display EGL returned (null is refused by eglInitialize without harm).
        if display.is_null() || unsafe { initialize(display, &mut egl_major, &mut egl_minor) } == 0
        {
            return Err(GlError::Context(
                "EGL's surfaceless platform (EGL_MESA_platform_surfaceless) is not available"
                    .into(),
            ));
        }
        let attributes = [
            CONTEXT_MAJOR_VERSION,
            major,
            CONTEXT_MINOR_VERSION,
            minor,
            CONTEXT_OPENGL_PROFILE_MASK,
            if compatibility {
                CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT
            } else {
                CONTEXT_OPENGL_CORE_PROFILE_BIT
            },
            NONE,
        ];
        // SAFETY: an initialised display; no config (EGL_KHR_no_config_context, which Mesa
        // has), no shared context, an EGL_NONE-terminated attribute list.
        let context = unsafe {
            bind_api(OPENGL_API);
            create_context(
                display,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                attributes.as_ptr(),
            )
        };
        if context.is_null() {
            return Err(GlError::Context(format!(
                "EGL made no OpenGL {major}.{minor} context of that profile"
            )));
        }
        // SAFETY: the display and context are valid; no surfaces (surfaceless).
        if unsafe {
            (egl.make_current)(display, std::ptr::null_mut(), std::ptr::null_mut(), context)
        } == 0
        {
            // SAFETY: ours, not current.
            unsafe { (egl.destroy_context)(display, context) };
            return Err(GlError::Context(
                "the surfaceless context could not be made current".into(),
            ));
        }
        let get = egl.get_proc_address;
        // SAFETY: eglGetProcAddress takes a NUL-terminated name (EGL 1.5 / Mesa return core
        // functions too).
        let loaded = Gl::load(&mut |name| unsafe { get(name.as_ptr()) });
        // SAFETY: the context is current on this thread and `loaded` was loaded for it.
        let engine = loaded.and_then(|gl| unsafe { GlFrameRunner::new(gl) });
        match engine {
            Ok(engine) => Ok(GlOffline {
                engine,
                egl,
                display,
                context,
            }),
            Err(e) => {
                // SAFETY: ours; released from this thread first.
                unsafe {
                    (egl.make_current)(
                        display,
                        std::ptr::null_mut(),
                        std::ptr::null_mut(),
                        std::ptr::null_mut(),
                    );
                    (egl.destroy_context)(display, context);
                }
                Err(e)
            }
        }
    }

    /// The engine on this context.
    pub fn engine(&mut self) -> &mut GlFrameRunner {
        &mut self.engine
    }

    /// The address of a GL function of this context (the tests drive GL state with it).
    pub fn proc_address(&self, name: &CStr) -> *const c_void {
        // SAFETY: a NUL-terminated name.
        unsafe { (self.egl.get_proc_address)(name.as_ptr()) }
    }

    /// A new texture of `internal_format` holding `bytes`: rows of raw texels, bottom row first
    /// (as GL stores them).
    pub fn create_texture(
        &mut self,
        internal_format: u32,
        size: (u32, u32),
        bytes: &[u8],
    ) -> Result<u32, GlError> {
        self.make_texture(internal_format, size, None, bytes)
    }

    /// A new 2D array texture of `layers` layers, `bytes` holding each layer's rows in turn
    /// (bottom row first).
    pub fn create_array_texture(
        &mut self,
        internal_format: u32,
        size: (u32, u32),
        layers: u32,
        bytes: &[u8],
    ) -> Result<u32, GlError> {
        self.make_texture(internal_format, size, Some(layers), bytes)
    }

    fn make_texture(
        &mut self,
        internal_format: u32,
        (width, height): (u32, u32),
        layers: Option<u32>,
        bytes: &[u8],
    ) -> Result<u32, GlError> {
        let format = GlFormat::of(internal_format)?;
        let depth = layers.unwrap_or(1);
        let need = width as usize
            * height as usize
            * depth as usize
            * format.pixel.bytes_per_pixel() as usize;
        if bytes.len() != need || need == 0 {
            return Err(GlError::Input(
                "texel data does not match the texture's size".into(),
            ));
        }
        let g = self.engine.gl();
        let (fmt, ty) = format.transfer;
        let (w, h, d) = (width as i32, height as i32, depth as i32);
        let mut texture = 0;
        // SAFETY: this engine's context is current on this thread (GlOffline is not Send); a
        // new texture of the given size, filled from client memory holding exactly its texels
        // (no unpack buffer bound, rows tightly packed with alignment 1).
        unsafe {
            (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, 0);
            (g.pixel_storei)(gl::UNPACK_ALIGNMENT, 1);
            let data = bytes.as_ptr().cast();
            if layers.is_some() {
                (g.create_textures)(gl::TEXTURE_2D_ARRAY, 1, &mut texture);
                (g.texture_storage_3d)(texture, 1, internal_format, w, h, d);
                (g.texture_sub_image_3d)(texture, 0, 0, 0, 0, w, h, d, fmt, ty, data);
            } else {
                (g.create_textures)(gl::TEXTURE_2D, 1, &mut texture);
                (g.texture_storage_2d)(texture, 1, internal_format, w, h);
                (g.texture_sub_image_2d)(texture, 0, 0, 0, w, h, fmt, ty, data);
            }
        }
        Ok(texture)
    }

    /// A texture's raw texels, bottom row first (every layer in turn of an array texture of
    /// `layers` layers; 1 for a 2D texture).
    pub fn read_texture_layers(
        &mut self,
        texture: u32,
        internal_format: u32,
        (width, height): (u32, u32),
        layers: u32,
    ) -> Result<Vec<u8>, GlError> {
        let format = GlFormat::of(internal_format)?;
        let texels = width as usize * height as usize * layers as usize;
        let mut out = vec![0u8; texels * format.pixel.bytes_per_pixel() as usize];
        let g = self.engine.gl();
        let (fmt, ty) = format.transfer;
        let (w, h, d) = (width as i32, height as i32, layers as i32);
        // SAFETY: the context is current; a texture of this size (the caller's); no pack
        // buffer bound, alignment 1: GL writes exactly out.len() bytes (bufSize says so).
        unsafe {
            (g.bind_buffer)(gl::PIXEL_PACK_BUFFER, 0);
            (g.pixel_storei)(gl::PACK_ALIGNMENT, 1);
            let len = out.len() as i32;
            (g.get_texture_sub_image)(
                texture,
                0,
                0,
                0,
                0,
                w,
                h,
                d,
                fmt,
                ty,
                len,
                out.as_mut_ptr().cast(),
            );
        }
        Ok(out)
    }

    /// A 2D texture's raw texels, bottom row first.
    pub fn read_texture(
        &mut self,
        texture: u32,
        internal_format: u32,
        size: (u32, u32),
    ) -> Result<Vec<u8>, GlError> {
        self.read_texture_layers(texture, internal_format, size, 1)
    }

    pub fn delete_texture(&mut self, texture: u32) {
        // SAFETY: the context is current; deleting a name is always valid.
        unsafe { (self.engine.gl().delete_textures)(1, &texture) };
    }

    /// Runs the engine on `views` until its programs are built (the tool may wait; a frame
    /// would pass through instead).
    pub fn enhance_views(&mut self, views: &[GlView], params: &Params) -> Result<(), GlError> {
        loop {
            // SAFETY: the context is current on this thread; the views' textures are this
            // context's (the caller's).
            match unsafe { self.engine.enhance(views, params)? } {
                Outcome::Enhanced => return Ok(()),
                Outcome::Compiling => std::thread::sleep(std::time::Duration::from_millis(1)),
            }
        }
    }

    /// Sets the background from a camera frame, prepared on the CPU as a live source does.
    pub fn set_camera(&mut self, camera: &RgbaImage, params: &Params) -> Result<(), GlError> {
        let texels = BlurredTexels::prepare(camera, BlurTaps::of(params));
        // SAFETY: the context is current on this thread.
        unsafe { self.engine.set_background(&texels) }
    }

    /// Enhances raw pixels (rows top first, 1 or 2 u32 per pixel) in a texture of
    /// `internal_format` against a camera frame, through `mapping`.
    pub fn enhance_raw_mapped(
        &mut self,
        pixels: &[u32],
        (region, internal_format): ((u32, u32), u32),
        camera: &RgbaImage,
        mapping: &CameraMapping,
        params: &Params,
    ) -> Result<Vec<u32>, GlError> {
        let bytes: Vec<u8> = pixels.iter().flat_map(|w| w.to_le_bytes()).collect();
        let row = bytes.len() / region.1.max(1) as usize;
        let flip =
            |b: &[u8]| -> Vec<u8> { b.chunks(row.max(1)).rev().flatten().copied().collect() };
        self.set_camera(camera, params)?;
        let texture = self.create_texture(internal_format, region, &flip(&bytes))?;
        let view = GlView {
            texture,
            target: GlTarget::Texture2D,
            internal_format,
            rect: (0, 0, region.0, region.1),
            mapping: *mapping,
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
        };
        let result = self
            .enhance_views(&[view], params)
            .and_then(|_| self.read_texture(texture, internal_format, region));
        self.delete_texture(texture);
        let out = flip(&result?);
        Ok(out
            .as_chunks::<4>()
            .0
            .iter()
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    /// `enhance_raw_mapped` with the manual FoV mapping of `params`.
    pub fn enhance_raw(
        &mut self,
        pixels: &[u32],
        region: (u32, u32),
        internal_format: u32,
        camera: &RgbaImage,
        params: &Params,
    ) -> Result<Vec<u32>, GlError> {
        let mapping = params.camera_mapping();
        self.enhance_raw_mapped(pixels, (region, internal_format), camera, &mapping, params)
    }
}

impl OfflineBackend for GlOffline {
    fn api(&self) -> &'static str {
        "opengl"
    }

    fn on_cpu(&self) -> bool {
        self.engine.caps().software
    }

    fn pixel_formats(&self) -> Vec<PixelFormat> {
        GlFormat::ALL
            .iter()
            .filter_map(|&internal| GlFormat::of(internal).ok())
            .map(|f| f.pixel)
            .collect()
    }

    fn enhance_pixels(
        &mut self,
        pixels: &[u32],
        (region, format): ((u32, u32), PixelFormat),
        camera: &RgbaImage,
        mapping: &CameraMapping,
        params: &Params,
    ) -> Result<Vec<u32>, String> {
        let internal = GlFormat::internal_of(format)
            .ok_or_else(|| format!("OpenGL has no internal format for {format:?}"))?;
        self.enhance_raw_mapped(pixels, (region, internal), camera, mapping, params)
            .map_err(|e| e.to_string())
    }
}

impl Drop for GlOffline {
    fn drop(&mut self) {
        // SAFETY: the context is current on this thread (not Send); it is released and then
        // destroyed, and the display is left initialised for other contexts of the process.
        unsafe {
            self.engine.destroy();
            (self.egl.make_current)(
                self.display,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            );
            (self.egl.destroy_context)(self.display, self.context);
        }
    }
}
