//! The app's GL state around the backend's calls: everything the recipe changes is read before
//! it runs and put back after it, so that the app finds exactly the state it left. The error
//! flag is not among it: the backend never calls glGetError (which would read and clear the
//! app's pending error, and GL has no call that sets it again) and checks what it is given
//! before using it, learning what failed from object status queries, so whatever error the
//! app had pending is still pending after the call. One error it cannot rule out: a driver out
//! of memory while the engine allocates a buffer or texture (glNamedBufferStorage,
//! glNamedBufferData, glTextureStorage2D, when an engine, a view size or a background size is
//! new, not every frame) records GL_OUT_OF_MEMORY, which an app with no error pending then
//! reads; the engine sees the failure in GL_BUFFER_SIZE or GL_TEXTURE_WIDTH. A binding
//! that could not be put back (an object alive only through it, active transform feedback) is
//! found before anything changes, and the call then does nothing (`GlError::Unrestorable`).
//! In a compatibility-profile context the pixel-transfer state (glPixelTransfer's scales,
//! biases, index shift and colour maps; GL_ARB_imaging's stages and colour matrix) would apply
//! to the recipe's transfers of non-integer texels: it is set neutral for the call and put back.

use crate::gpu::core::interface::{
    BINDING_APP_IMAGE, BINDING_BLURRED_TEXELS, BINDING_PERCEPTUAL, BINDING_PIXELS, BINDING_TILES,
};
use crate::gpu::opengl::device::caps::Caps;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;

/// The indexed shader storage bindings the programs use.
const STORAGE_SLOTS: [u32; 3] = [BINDING_PIXELS, BINDING_TILES, BINDING_PERCEPTUAL];

/// The pixel store parameters, pack and unpack.
const PIXEL_STORE: [gl::Enum; 16] = [
    gl::PACK_SWAP_BYTES,
    gl::PACK_LSB_FIRST,
    gl::PACK_ROW_LENGTH,
    gl::PACK_SKIP_ROWS,
    gl::PACK_SKIP_PIXELS,
    gl::PACK_ALIGNMENT,
    gl::PACK_SKIP_IMAGES,
    gl::PACK_IMAGE_HEIGHT,
    gl::UNPACK_SWAP_BYTES,
    gl::UNPACK_LSB_FIRST,
    gl::UNPACK_ROW_LENGTH,
    gl::UNPACK_SKIP_ROWS,
    gl::UNPACK_SKIP_PIXELS,
    gl::UNPACK_ALIGNMENT,
    gl::UNPACK_SKIP_IMAGES,
    gl::UNPACK_IMAGE_HEIGHT,
];

/// Their defaults, which the recipe's transfers assume (tightly packed rows).
const PIXEL_STORE_DEFAULTS: [gl::Int; 16] = [0, 0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 0, 0, 4, 0, 0];

/// One indexed buffer binding: the buffer, its offset and size (0 and 0 for a whole-buffer
/// binding).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Indexed {
    buffer: u32,
    start: i64,
    size: i64,
}

/// The image unit the in-place programs store through, as glGetIntegeri_v reads it: name,
/// level, layered, layer, access, format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct ImageUnit([i32; 6]);

const IMAGE_UNIT_QUERIES: [gl::Enum; 6] = [
    gl::IMAGE_BINDING_NAME,
    gl::IMAGE_BINDING_LEVEL,
    gl::IMAGE_BINDING_LAYERED,
    gl::IMAGE_BINDING_LAYER,
    gl::IMAGE_BINDING_ACCESS,
    gl::IMAGE_BINDING_FORMAT,
];

impl ImageUnit {
    fn save(g: &Gl) -> ImageUnit {
        ImageUnit(IMAGE_UNIT_QUERIES.map(|q| {
            let mut v = 0;
            // SAFETY: an indexed query of image unit 6 (< GL_MAX_IMAGE_UNITS, at least 8 in
            // 4.3) into a valid output.
            unsafe { (g.get_integeri_v)(q, BINDING_APP_IMAGE, &mut v) };
            v
        }))
    }

    fn restore(&self, g: &Gl) {
        let [name, level, layered, layer, access, format] = self.0;
        // SAFETY: values read from this unit in `save` (GL's own defaults when unbound).
        unsafe {
            (g.bind_image_texture)(
                BINDING_APP_IMAGE,
                name as u32,
                level,
                u8::from(layered != 0),
                layer,
                access as u32,
                format as u32,
            )
        };
    }
}

/// The app's debug output (GL_DEBUG_OUTPUT, core since 4.3) off while a call of the backend
/// runs, on again when this is dropped if it was on: the driver's messages about the layer's
/// own work (a compile log, a buffer's placement, a slow path) are no business of the app's
/// callback or message log. Turning it off raises no message and no error, unlike a debug
/// group (glPushDebugGroup and glPopDebugGroup each send the app's callback a message), and
/// leaves the app's message filters untouched. Holds no borrow: the engine stays usable.
pub struct DebugOutputOff {
    /// glEnable, to turn it on again; None when it was off.
    enable: Option<unsafe extern "system" fn(gl::Enum)>,
}

impl DebugOutputOff {
    /// Turns the current context's debug output off, if on.
    ///
    /// # Safety
    /// A context of `g`'s driver is current on this thread, and stays current until this is
    /// dropped.
    pub unsafe fn new(g: &Gl) -> DebugOutputOff {
        // SAFETY: a core 4.3 capability, the context being 4.5 (the caller's contract).
        let on = unsafe { (g.is_enabled)(gl::DEBUG_OUTPUT) } != 0;
        if on {
            // SAFETY: as above.
            unsafe { (g.disable)(gl::DEBUG_OUTPUT) };
        }
        DebugOutputOff {
            enable: on.then_some(g.enable),
        }
    }
}

impl Drop for DebugOutputOff {
    fn drop(&mut self) {
        if let Some(enable) = self.enable {
            // SAFETY: the same context is current (`new`'s contract).
            unsafe { enable(gl::DEBUG_OUTPUT) };
        }
    }
}

/// The compatibility profile's pixel-transfer state, as far as it differs from the neutral
/// one: only that is set neutral for the call and put back (a core context has none).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct PixelTransfer {
    /// Each glPixelTransfer parameter that was not neutral, with the app's value (f32 bits).
    changed: Vec<(gl::Enum, u32)>,
    /// The imaging stages the app had enabled.
    stages: Vec<gl::Enum>,
    /// The app's colour matrix (f32 bits) and matrix mode, when the matrix was not identity.
    color_matrix: Option<([u32; 16], i32)>,
}

const IDENTITY: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

impl PixelTransfer {
    /// Reads the state (nothing on a core context); changes nothing.
    fn save(g: &Gl, caps: &Caps) -> PixelTransfer {
        let mut saved = PixelTransfer::default();
        if !caps.compatibility {
            return saved;
        }
        let imaging: &[(gl::Enum, f32)] = if caps.imaging {
            &gl::IMAGING_TRANSFER_NEUTRAL
        } else {
            &[]
        };
        for &(p, neutral) in gl::PIXEL_TRANSFER_NEUTRAL.iter().chain(imaging) {
            let mut v = 0.0f32;
            // SAFETY: a single-valued pixel-transfer query of a compatibility context (the
            // imaging ones only with GL_ARB_imaging) into a valid f32.
            unsafe { (g.get_floatv)(p, &mut v) };
            if v != neutral {
                saved.changed.push((p, v.to_bits()));
            }
        }
        if caps.imaging {
            saved.stages = gl::IMAGING_STAGES
                .into_iter()
                // SAFETY: GL_ARB_imaging's capabilities, which the context has.
                .filter(|&c| unsafe { (g.is_enabled)(c) } != 0)
                .collect();
            let mut m = [0.0f32; 16];
            // SAFETY: GL_COLOR_MATRIX is 16 floats (GL_ARB_imaging).
            unsafe { (g.get_floatv)(gl::COLOR_MATRIX, m.as_mut_ptr()) };
            if m != IDENTITY {
                saved.color_matrix = Some((m.map(f32::to_bits), int(g, gl::MATRIX_MODE)));
            }
        }
        saved
    }

    /// Sets what differed to its neutral value.
    fn neutralise(&self, g: &Gl) {
        let neutral = |p: gl::Enum| {
            gl::PIXEL_TRANSFER_NEUTRAL
                .iter()
                .chain(&gl::IMAGING_TRANSFER_NEUTRAL)
                .find(|(q, _)| *q == p)
                .map_or(0.0, |&(_, v)| v)
        };
        if let Some(transfer) = g.pixel_transferf {
            for &(p, _) in &self.changed {
                // SAFETY: a parameter read in `save`, set to its default.
                unsafe { transfer(p, neutral(p)) };
            }
        }
        for &c in &self.stages {
            // SAFETY: a capability the context has (read in `save`).
            unsafe { (g.disable)(c) };
        }
        if let (Some((_, mode)), Some(matrix_mode), Some(load)) =
            (self.color_matrix, g.matrix_mode, g.load_matrixf)
        {
            // SAFETY: GL_ARB_imaging's colour matrix (Caps checked the entry points); the
            // app's matrix mode, read in `save`, is made current again.
            unsafe {
                matrix_mode(gl::COLOR);
                load(IDENTITY.as_ptr());
                matrix_mode(mode as u32);
            }
        }
    }

    fn restore(&self, g: &Gl) {
        if let Some(transfer) = g.pixel_transferf {
            for &(p, v) in &self.changed {
                // SAFETY: the app's value of a parameter, read in `save`.
                unsafe { transfer(p, f32::from_bits(v)) };
            }
        }
        for &c in &self.stages {
            // SAFETY: as in `neutralise`.
            unsafe { (g.enable)(c) };
        }
        if let (Some((m, mode)), Some(matrix_mode), Some(load)) =
            (self.color_matrix, g.matrix_mode, g.load_matrixf)
        {
            let m = m.map(f32::from_bits);
            // SAFETY: as in `neutralise`, loading the app's matrix.
            unsafe {
                matrix_mode(gl::COLOR);
                load(m.as_ptr());
                matrix_mode(mode as u32);
            }
        }
    }
}

/// The app's state saved, put back when this is dropped: also when the recipe panics between
/// (the panic is caught at the layer's boundary, and the app finds its state as it left it).
pub struct StateGuard<'a> {
    g: &'a Gl,
    saved: SavedState,
}

impl Drop for StateGuard<'_> {
    fn drop(&mut self) {
        self.saved.restore(self.g);
    }
}

/// The state the recipe touches, as the app left it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SavedState {
    program: i32,
    pipeline: i32,
    active_texture: i32,
    /// The 2D texture and sampler bound to the unit the programs sample on.
    texture: i32,
    sampler: i32,
    storage: [Indexed; STORAGE_SLOTS.len()],
    image_unit: ImageUnit,
    storage_generic: i32,
    pack_buffer: i32,
    unpack_buffer: i32,
    indirect_buffer: i32,
    draw_framebuffer: i32,
    read_framebuffer: i32,
    framebuffer_srgb: bool,
    pixel_store: [i32; 16],
    pixel_transfer: PixelTransfer,
}

fn int(g: &Gl, name: gl::Enum) -> i32 {
    let mut v = 0;
    // SAFETY: a single-valued state query into a valid i32 (the context is 4.3 or later).
    unsafe { (g.get_integerv)(name, &mut v) };
    v
}

/// The texture unit the programs sample the background on (its binding number).
fn sample_unit() -> gl::Enum {
    gl::TEXTURE0 + BINDING_BLURRED_TEXELS
}

impl SavedState {
    /// Reads the state and sets the pixel store (and a compatibility context's pixel
    /// transfer) to the defaults the recipe's transfers need; or, changing nothing, why a
    /// binding could not be put back afterwards.
    pub fn save(g: &Gl, caps: &Caps) -> Result<SavedState, GlError> {
        let active_texture = int(g, gl::ACTIVE_TEXTURE);
        // SAFETY: a valid texture unit (binding 5 < GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, at
        // least 80 in 4.3); put back in `restore`.
        unsafe { (g.active_texture)(sample_unit()) };
        let texture = int(g, gl::TEXTURE_BINDING_2D);
        let sampler = int(g, gl::SAMPLER_BINDING);
        // SAFETY: the app's own active unit, just read.
        unsafe { (g.active_texture)(active_texture as u32) };
        let storage = STORAGE_SLOTS.map(|slot| {
            let (mut buffer, mut start, mut size) = (0, 0i64, 0i64);
            // SAFETY: indexed queries of a binding below GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS
            // (at least 8 in 4.3) into valid outputs.
            unsafe {
                (g.get_integeri_v)(gl::SHADER_STORAGE_BUFFER_BINDING, slot, &mut buffer);
                (g.get_integer64i_v)(gl::SHADER_STORAGE_BUFFER_START, slot, &mut start);
                (g.get_integer64i_v)(gl::SHADER_STORAGE_BUFFER_SIZE, slot, &mut size);
            }
            Indexed {
                buffer: buffer as u32,
                start,
                size,
            }
        });
        let pixel_store = PIXEL_STORE.map(|p| int(g, p));
        let saved = SavedState {
            program: int(g, gl::CURRENT_PROGRAM),
            pipeline: int(g, gl::PROGRAM_PIPELINE_BINDING),
            active_texture,
            texture,
            sampler,
            storage,
            image_unit: ImageUnit::save(g),
            storage_generic: int(g, gl::SHADER_STORAGE_BUFFER_BINDING),
            pack_buffer: int(g, gl::PIXEL_PACK_BUFFER_BINDING),
            unpack_buffer: int(g, gl::PIXEL_UNPACK_BUFFER_BINDING),
            indirect_buffer: int(g, gl::DISPATCH_INDIRECT_BUFFER_BINDING),
            draw_framebuffer: int(g, gl::DRAW_FRAMEBUFFER_BINDING),
            read_framebuffer: int(g, gl::READ_FRAMEBUFFER_BINDING),
            // SAFETY: GL_FRAMEBUFFER_SRGB is a valid capability in core 3.0+.
            framebuffer_srgb: unsafe { (g.is_enabled)(gl::FRAMEBUFFER_SRGB) } != 0,
            pixel_store,
            pixel_transfer: PixelTransfer::save(g, caps),
        };
        if let Some(why) = saved.unrestorable(g) {
            return Err(GlError::Unrestorable(why));
        }
        for (p, v) in PIXEL_STORE.iter().zip(PIXEL_STORE_DEFAULTS) {
            // SAFETY: valid pixel store parameters and values.
            unsafe { (g.pixel_storei)(*p, v) };
        }
        saved.pixel_transfer.neutralise(g);
        Ok(saved)
    }

    /// `save`, restored when the guard is dropped.
    pub fn guard<'a>(g: &'a Gl, caps: &Caps) -> Result<StateGuard<'a>, GlError> {
        Ok(StateGuard {
            g,
            saved: SavedState::save(g, caps)?,
        })
    }

    /// Why a saved binding could not be bound again once the recipe has bound its own, if so:
    /// an object kept alive only by that binding (a program deleted while current, a texture,
    /// buffer or sampler deleted through a shared context) would be freed when unbound, and
    /// binding its name again would raise an error into the app's flag; active transform
    /// feedback makes glUseProgram itself an error.
    fn unrestorable(&self, g: &Gl) -> Option<&'static str> {
        let gone = |name: i32, is: unsafe extern "system" fn(u32) -> u8| {
            // SAFETY: glIs* take any name and raise no error.
            name != 0 && unsafe { is(name as u32) } == 0
        };
        if self.program != 0 {
            let mut deleted = 0;
            // SAFETY: a program name that is current (so it exists); a valid pname.
            unsafe { (g.get_programiv)(self.program as u32, gl::DELETE_STATUS, &mut deleted) };
            if deleted != 0 {
                return Some("the app's current program is deleted (kept alive by its binding)");
            }
        }
        if int(g, gl::TRANSFORM_FEEDBACK_ACTIVE) != 0 && int(g, gl::TRANSFORM_FEEDBACK_PAUSED) == 0
        {
            return Some("the app's transform feedback is active");
        }
        let textures = [self.texture, self.image_unit.0[0]];
        if textures.iter().any(|&t| gone(t, g.is_texture)) {
            return Some("a texture the app has bound is deleted");
        }
        let buffers = self.storage.iter().map(|b| b.buffer as i32).chain([
            self.storage_generic,
            self.pack_buffer,
            self.unpack_buffer,
            self.indirect_buffer,
        ]);
        if buffers.into_iter().any(|b| gone(b, g.is_buffer)) {
            return Some("a buffer the app has bound is deleted");
        }
        if gone(self.sampler, g.is_sampler) {
            return Some("a sampler the app has bound is deleted");
        }
        if gone(self.pipeline, g.is_program_pipeline) {
            return Some("the app's program pipeline is deleted");
        }
        None
    }

    /// Puts every value back. Each was valid when read, and objects the app named stay alive
    /// across the call, so none of these calls raises an error.
    pub fn restore(&self, g: &Gl) {
        // SAFETY: every value was read from this context in `save`; the calls take them back
        // in the order that leaves the generic bindings last (glBindBufferRange sets both).
        unsafe {
            (g.active_texture)(sample_unit());
            (g.bind_texture)(gl::TEXTURE_2D, self.texture as u32);
            (g.bind_sampler)(BINDING_BLURRED_TEXELS, self.sampler as u32);
            (g.active_texture)(self.active_texture as u32);
            for (slot, b) in STORAGE_SLOTS.iter().zip(&self.storage) {
                if b.buffer != 0 && b.size > 0 {
                    let (start, size) = (b.start as isize, b.size as isize);
                    (g.bind_buffer_range)(gl::SHADER_STORAGE_BUFFER, *slot, b.buffer, start, size);
                } else {
                    (g.bind_buffer_base)(gl::SHADER_STORAGE_BUFFER, *slot, b.buffer);
                }
            }
            (g.bind_buffer)(gl::SHADER_STORAGE_BUFFER, self.storage_generic as u32);
            self.image_unit.restore(g);
            (g.bind_buffer)(gl::PIXEL_PACK_BUFFER, self.pack_buffer as u32);
            (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, self.unpack_buffer as u32);
            (g.bind_buffer)(gl::DISPATCH_INDIRECT_BUFFER, self.indirect_buffer as u32);
            (g.bind_framebuffer)(gl::DRAW_FRAMEBUFFER, self.draw_framebuffer as u32);
            (g.bind_framebuffer)(gl::READ_FRAMEBUFFER, self.read_framebuffer as u32);
            if self.framebuffer_srgb {
                (g.enable)(gl::FRAMEBUFFER_SRGB);
            } else {
                (g.disable)(gl::FRAMEBUFFER_SRGB);
            }
            for (p, v) in PIXEL_STORE.iter().zip(self.pixel_store) {
                (g.pixel_storei)(*p, v);
            }
            self.pixel_transfer.restore(g);
            (g.use_program)(self.program as u32);
            (g.bind_program_pipeline)(self.pipeline as u32);
        }
    }
}
