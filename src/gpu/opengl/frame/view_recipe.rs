//! One view's recipe on the app's context: its buffers made once per slot and size, the region
//! bound in place (an image unit, through a texture view for sRGB) or copied into a buffer, the
//! view's steps run (src/gpu/opengl/record.rs) and the region copied back.

use super::frame_runner::{rows_from_bottom, GlFrameRunner, StoreThrough};
use super::frame_view::{GlTarget, GlView};
use super::region::{read_region, write_region};
use crate::algorithm::params::Params;
use crate::algorithm::perception::frequency::ViewGeometry;
use crate::gpu::core::interface::{
    BINDING_APP_IMAGE, BINDING_BLURRED_TEXELS, BINDING_PERCEPTUAL, BINDING_PIXELS, BINDING_TILES,
    TILE, TILE_LIST_HEADER_WORDS,
};
use crate::gpu::core::plan::Step;
use crate::gpu::core::push_constants::PushConstants;
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;
use crate::gpu::opengl::record::run_steps;

fn buffer_size(g: &Gl, buffer: u32) -> i32 {
    let mut v = 0;
    // SAFETY: a buffer this engine made; a valid pname.
    unsafe { (g.get_named_buffer_parameteriv)(buffer, gl::BUFFER_SIZE, &mut v) };
    v
}

/// A new buffer object of `bytes` bytes (uninitialised), or the allocation error: GL_BUFFER_SIZE
/// tells whether the driver made it.
fn new_buffer(g: &Gl, bytes: usize, what: &'static str) -> Result<u32, GlError> {
    let mut buffer = 0;
    // SAFETY: one name into a valid output; data null allocates without copying.
    unsafe {
        (g.create_buffers)(1, &mut buffer);
        (g.named_buffer_data)(buffer, bytes as isize, std::ptr::null(), gl::DYNAMIC_COPY);
    }
    if buffer_size(g, buffer) as usize != bytes {
        // SAFETY: ours.
        unsafe { (g.delete_buffers)(1, &buffer) };
        return Err(GlError::Allocation(what));
    }
    Ok(buffer)
}

impl GlFrameRunner {
    /// Makes slot `k`'s buffers large enough for the view (no pixel buffer in place).
    pub(super) fn ensure_buffers(
        &mut self,
        k: usize,
        v: &GlView,
        in_place: bool,
    ) -> Result<(), GlError> {
        let g = &self.gl;
        let format = GlFormat::of(v.internal_format)?;
        let (w, h) = (v.rect.2 as usize, v.rect.3 as usize);
        // 16 bytes beyond the rows: the narrow access reads up to three words past the last
        // pixel of a group.
        let pixels = (w * h * format.pixel.bytes_per_pixel() as usize).div_ceil(16) * 16 + 16;
        let tiles = w.div_ceil(TILE as usize) * h.div_ceil(TILE as usize);
        let tile_bytes = (TILE_LIST_HEADER_WORDS as usize + tiles) * 4;
        let slot = &mut self.views[k];
        if !in_place && slot.pixel_capacity < pixels {
            if slot.pixels != 0 {
                // SAFETY: ours.
                unsafe { (g.delete_buffers)(1, &slot.pixels) };
                slot.pixels = 0;
                slot.pixel_capacity = 0;
            }
            slot.pixels = new_buffer(g, pixels, "view buffer")?;
            slot.pixel_capacity = pixels;
        }
        if slot.tile_capacity < tile_bytes {
            if slot.tiles != 0 {
                // SAFETY: ours.
                unsafe { (g.delete_buffers)(1, &slot.tiles) };
                slot.tiles = 0;
                slot.tile_capacity = 0;
            }
            slot.tiles = new_buffer(g, tile_bytes, "tile list")?;
            slot.tile_capacity = tile_bytes;
        }
        Ok(())
    }

    /// Uploads the view's perceptual model (src/gpu/core/perceptual_words.rs) into slot `k`'s
    /// buffer where its method reads one and the buffer does not hold it yet (the buffer made
    /// on first use).
    pub(super) fn upload_model(
        &mut self,
        k: usize,
        v: &GlView,
        params: &Params,
        bg_size: (u32, u32),
    ) -> Result<(), GlError> {
        let g = &self.gl;
        let slot = &mut self.views[k];
        let geometry = ViewGeometry {
            mapping: &v.mapping,
            display_width: v.rect.2,
            camera_width: bg_size.0,
            pixels_per_degree: v.pixels_per_degree,
        };
        let Some(words) = slot.perceptual_words.to_upload(params, &geometry) else {
            return Ok(());
        };
        let bytes = std::mem::size_of_val(words);
        if slot.perceptual == 0 {
            slot.perceptual = new_buffer(g, bytes, "perceptual model")?;
        }
        // SAFETY: the slot's buffer of exactly `bytes` bytes (PERCEPTUAL_WORDS words), from
        // words that live through the call.
        unsafe {
            (g.named_buffer_sub_data)(slot.perceptual, 0, bytes as isize, words.as_ptr().cast())
        };
        slot.perceptual_words.set_held();
        Ok(())
    }

    /// The recipe for one view (state saved by the caller; every object checked before).
    pub(super) fn run_view(
        &self,
        k: usize,
        v: &GlView,
        (params, steps): (&Params, &[Step]),
        bg_size: (u32, u32),
        ids: [usize; 3],
    ) {
        let g = &self.gl;
        let format = GlFormat::of(v.internal_format).expect("checked");
        let (x, y, w, h) = v.rect;
        let through = self.store_through(v);
        let bytes = w as usize * h as usize * format.pixel.bytes_per_pixel() as usize;
        let buffers = &self.views[k];
        let mapping = rows_from_bottom(&v.mapping);
        let mut push = PushConstants::new(params, bg_size, (w, h), &mapping);
        // 16 bits each (interface.rs, region_origin), as on Vulkan; only in place reads it.
        push.region_origin = (x & 0xffff) | (y << 16);
        let [classify, finish_tiles, enhance] = ids.map(|id| self.programs.get(id));
        classify.set_params(g, &push);
        enhance.set_params(g, &push);
        let bg = self.background.as_ref().expect("checked by the caller");
        // SAFETY: every object is this engine's or the view's checked texture; the region lies
        // inside the texture and the buffer holds it (with the pixel store at its defaults,
        // rows tightly packed from offset 0); bindings are within the 4.3 minimums and put
        // back by the caller's SavedState.
        unsafe {
            let view_texture = match through {
                Some(t) => self.bind_app_image(v, t),
                None => {
                    (g.bind_buffer)(gl::PIXEL_PACK_BUFFER, buffers.pixels);
                    read_region(g, v, format, v.rect, (std::ptr::null_mut(), bytes));
                    let bound = (bytes.div_ceil(16) * 16 + 16) as isize;
                    (g.bind_buffer_range)(
                        gl::SHADER_STORAGE_BUFFER,
                        BINDING_PIXELS,
                        buffers.pixels,
                        0,
                        bound,
                    );
                    0
                }
            };
            (g.bind_buffer_base)(gl::SHADER_STORAGE_BUFFER, BINDING_TILES, buffers.tiles);
            if buffers.perceptual != 0 {
                (g.bind_buffer_base)(
                    gl::SHADER_STORAGE_BUFFER,
                    BINDING_PERCEPTUAL,
                    buffers.perceptual,
                );
            }
            (g.active_texture)(gl::TEXTURE0 + BINDING_BLURRED_TEXELS);
            (g.bind_texture)(gl::TEXTURE_2D, bg.texture);
            (g.bind_sampler)(BINDING_BLURRED_TEXELS, 0);
            (g.bind_buffer)(gl::DISPATCH_INDIRECT_BUFFER, buffers.tiles);
            run_steps(g, steps, buffers.tiles, [classify, finish_tiles, enhance]);
            if through.is_some() {
                // The stores reach whatever reads the texture next: the app's sampling,
                // blits, or the runtime's compositor through the memory it imported.
                (g.memory_barrier)(gl::ALL_BARRIER_BITS);
                if view_texture != 0 {
                    (g.delete_textures)(1, &view_texture);
                }
                return;
            }
            (g.memory_barrier)(
                gl::PIXEL_BUFFER_BARRIER_BIT
                    | gl::TEXTURE_UPDATE_BARRIER_BIT
                    | gl::BUFFER_UPDATE_BARRIER_BIT,
            );
            (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, buffers.pixels);
            write_region(g, v, format, v.rect, std::ptr::null());
        }
    }

    /// Binds the view's texel layer to the in-place programs' image unit, through a new
    /// texture view where `through` says so; that view's name (0 for none), for the caller to
    /// delete once the passes are recorded (GL keeps it alive while they run).
    ///
    /// # Safety
    /// The engine's context is current; `v` is checked and `through` is `store_through(v)`.
    unsafe fn bind_app_image(&self, v: &GlView, through: StoreThrough) -> u32 {
        let g = &self.gl;
        let layer = match v.target {
            GlTarget::Texture2D => 0,
            GlTarget::Texture2DArray { layer } => layer,
        };
        match through {
            StoreThrough::Texture(unit_format) => {
                // SAFETY: a checked texture and an image unit format of its size (GL's
                // compatibility by size); one layer, not layered.
                unsafe {
                    (g.bind_image_texture)(
                        BINDING_APP_IMAGE,
                        v.texture,
                        0,
                        0,
                        layer as i32,
                        gl::READ_WRITE,
                        unit_format,
                    )
                };
                0
            }
            StoreThrough::View(view_format) => {
                let mut view = 0;
                // SAFETY: a name from glGenTextures, not yet bound, made a 2D view of one
                // layer and level 0 of an immutable texture (checked by store_through) in a
                // format of its size class (GL_SRGB8_ALPHA8 -> GL_RGBA8).
                unsafe {
                    (g.gen_textures)(1, &mut view);
                    (g.texture_view)(view, gl::TEXTURE_2D, v.texture, view_format, 0, 1, layer, 1);
                    (g.bind_image_texture)(
                        BINDING_APP_IMAGE,
                        view,
                        0,
                        0,
                        0,
                        gl::READ_WRITE,
                        view_format,
                    );
                }
                view
            }
        }
    }
}
