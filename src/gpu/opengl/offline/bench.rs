//! `contrastxr bench --engine opengl`: the OpenGL engine's GPU time (GL_TIME_ELAPSED queries)
//! on the offline EGL context, in the columns of the Vulkan benchmark (gpu/vulkan/offline/bench.rs):
//! the plain copy floor (glCopyImageSubData of each view into a texture of the same format),
//! the frame through a buffer (the engine's call with views copied into a buffer object and
//! back), the buffer copies alone, the frame in place (the engine's call storing into the
//! texture through an image unit: the enhancement with nothing around it, so also the
//! enhancement's figure) and the background upload. On a CPU driver, whose timer queries leave
//! out the work it does at call time (llvmpipe copies inside glCopyImageSubData), each span is
//! the wall time between two glFinish instead. The views are GL_SRGB8_ALPHA8 textures of
//! immutable storage, as a runtime imports them, restored from a pristine copy before each run
//! outside the timed spans.

use super::offline_engine::GlOffline;
use crate::algorithm::params::Params;
use crate::algorithm::perception::frequency::DEFAULT_PIXELS_PER_DEGREE;
use crate::gpu::core::bench::{
    camera_frame, content_pixel, median, Ablation, BenchCase, BenchResult, Content, CAMERA_SIZE,
    WARM_UP_RUNS,
};
use crate::gpu::core::blurred_texels::{BlurTaps, BlurredTexels};
use crate::gpu::core::ClassifyChoice;
use crate::gpu::opengl::conv::GlFormat;
use crate::gpu::opengl::device::functions::{self as gl, Gl};
use crate::gpu::opengl::device::GlError;
use crate::gpu::opengl::frame::{read_region, write_region};
use crate::gpu::opengl::frame::{GlTarget, GlView};
use crate::image::RgbaImage;

/// The spans timed in each run.
const COPY: usize = 0;
const FRAME: usize = 1;
const TRANSFERS: usize = 2;
const IN_PLACE: usize = 3;
const UPLOAD: usize = 4;
const SPANS: usize = 5;

/// The textures a case runs on: per view the app's texture, its pristine copy and the copy
/// floor's destination; a buffer object for the transfers alone.
struct GlRig {
    views: Vec<GlView>,
    pristine: Vec<u32>,
    scratch: Vec<u32>,
    buffer: u32,
    queries: [u32; SPANS],
    /// Each span's wall time in ms, on a CPU driver (`Caps::software`).
    walls: [f64; SPANS],
}

/// The region's texels of `content`, rows bottom first, and the foreground fraction.
fn content_texels(content: Content, (w, h): (u32, u32)) -> (Vec<u8>, f64) {
    let mut bytes = Vec::with_capacity((w * h * 4) as usize);
    let mut foreground = 0usize;
    for y in (0..h).rev() {
        for x in 0..w {
            let p = content_pixel(content, x, y, w, h);
            foreground += usize::from(p & 0x00ff_ffff != 0 && p >> 24 != 0);
            bytes.extend(p.to_le_bytes());
        }
    }
    (bytes, foreground as f64 / f64::from(w * h))
}

impl GlOffline {
    /// Times `case` (its `in_place` and `image_copy` are ignored: the frame in place is always
    /// timed, and OpenGL has no image-copy path).
    pub fn bench(&mut self, case: &BenchCase, params: &Params) -> Result<BenchResult, GlError> {
        params.validate().map_err(GlError::Input)?;
        if case.ablation == Ablation::SharedFetch {
            return Err(GlError::Input(
                "the OpenGL engine has no shared fetches to ablate".into(),
            ));
        }
        let internal = gl::SRGB8_ALPHA8;
        let (texels, foreground) = content_texels(case.content, case.region);
        let mut rig = GlRig {
            views: Vec::new(),
            pristine: Vec::new(),
            scratch: Vec::new(),
            buffer: 0,
            queries: [0; SPANS],
            walls: [0.0; SPANS],
        };
        for _ in 0..case.views {
            let texture = self.create_texture(internal, case.region, &texels)?;
            rig.views.push(GlView {
                texture,
                target: GlTarget::Texture2D,
                internal_format: internal,
                rect: (0, 0, case.region.0, case.region.1),
                mapping: params.camera_mapping(),
                pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            });
            rig.pristine
                .push(self.create_texture(internal, case.region, &texels)?);
            rig.scratch
                .push(self.create_texture(internal, case.region, &texels)?);
        }
        let engine = self.engine();
        engine.set_ablation(case.ablation.bits());
        engine.set_classify(case.ablation.classify());
        let result = self.bench_with(&mut rig, case, params, texels.len(), foreground);
        self.engine().set_ablation(0);
        self.engine().set_classify(ClassifyChoice::Own);
        self.destroy_rig(rig);
        result
    }

    fn bench_with(
        &mut self,
        rig: &mut GlRig,
        case: &BenchCase,
        params: &Params,
        bytes: usize,
        foreground: f64,
    ) -> Result<BenchResult, GlError> {
        let (w, h) = CAMERA_SIZE;
        let camera = RgbaImage {
            width: w,
            height: h,
            pixels: camera_frame(CAMERA_SIZE),
            has_alpha: false,
        };
        self.set_camera(&camera, params)?;
        {
            let g = self.engine().gl();
            // SAFETY: the context is current (GlOffline is not Send); outputs of the right
            // sizes; a buffer of `bytes` for one view's texels.
            unsafe {
                (g.gen_queries)(SPANS as i32, rig.queries.as_mut_ptr());
                (g.create_buffers)(1, &mut rig.buffer);
                (g.named_buffer_data)(
                    rig.buffer,
                    bytes as isize,
                    std::ptr::null(),
                    gl::DYNAMIC_COPY,
                );
            }
        }
        // Both paths' programs built before anything is timed.
        for in_place in [false, true] {
            self.engine().set_in_place(in_place);
            self.enhance_views(&rig.views, params)?;
        }
        let mut samples: [Vec<f64>; SPANS] = Default::default();
        for run in 0..WARM_UP_RUNS + case.runs {
            let times = self.timed_run(rig, params, &camera)?;
            if run >= WARM_UP_RUNS {
                for (s, t) in samples.iter_mut().zip(times) {
                    s.push(t);
                }
            }
        }
        let ms = samples.map(median);
        Ok(BenchResult {
            case: *case,
            copy_ms: ms[COPY],
            copy_wide_ms: None,
            enhance_ms: ms[IN_PLACE],
            frame_ms: ms[FRAME],
            image_copy_ms: ms[TRANSFERS],
            frame_in_place_ms: Some(ms[IN_PLACE]),
            frame_image_copy_ms: None,
            image_copy_copies_ms: None,
            frame_image_copy_tiles_ms: None,
            frame_sampled_tiles_ms: None,
            background_ms: ms[UPLOAD],
            foreground,
        })
    }

    /// One run: each span's GPU time in ms.
    fn timed_run(
        &mut self,
        rig: &mut GlRig,
        params: &Params,
        camera: &RgbaImage,
    ) -> Result<[f64; SPANS], GlError> {
        self.restore_views(rig);
        let (views, scratch) = (rig.views.clone(), rig.scratch.clone());
        self.span(rig, COPY, |o| {
            copy_views(o.engine().gl(), &views, &scratch);
            Ok(())
        })?;
        self.engine().set_in_place(false);
        self.span(rig, FRAME, |o| o.enhance_views(&views, params))?;
        self.restore_views(rig);
        let buffer = rig.buffer;
        self.span(rig, TRANSFERS, |o| {
            transfers(o.engine().gl(), &views, buffer);
            Ok(())
        })?;
        self.restore_views(rig);
        self.engine().set_in_place(true);
        self.span(rig, IN_PLACE, |o| o.enhance_views(&views, params))?;
        // A new frame's texels (prepared on the CPU, as a source's thread does) uploaded.
        let texels = BlurredTexels::prepare(camera, BlurTaps::of(params));
        self.span(rig, UPLOAD, |o| {
            // SAFETY: the context is current on this thread.
            unsafe { o.engine().set_background(&texels) }
        })?;
        if self.engine().caps().software {
            return Ok(rig.walls);
        }
        let g = self.engine().gl();
        Ok(rig.queries.map(|q| {
            let mut ns = 0u64;
            // SAFETY: a query of this context that has ended; waits for its result.
            unsafe { (g.get_query_objectui64v)(q, gl::QUERY_RESULT, &mut ns) };
            ns as f64 * 1e-6
        }))
    }

    /// Runs `f` inside the time-elapsed query of `span`, begun once earlier work is done (between
    /// two glFinish on a CPU driver).
    fn span(
        &mut self,
        rig: &mut GlRig,
        span: usize,
        f: impl FnOnce(&mut GlOffline) -> Result<(), GlError>,
    ) -> Result<(), GlError> {
        if self.engine().caps().software {
            let g = self.engine().gl();
            // SAFETY: the context is current on this thread.
            unsafe { (g.finish)() };
            let started = std::time::Instant::now();
            let r = f(self);
            // SAFETY: as above.
            unsafe { (self.engine().gl().finish)() };
            rig.walls[span] = started.elapsed().as_secs_f64() * 1e3;
            return r;
        }
        // All earlier work done first (the untimed restore's copies included), as the Vulkan
        // bench's barrier before each span: a GPU may still be copying when the query begins.
        // SAFETY: the context is current; a query name of this context, no other query active.
        unsafe {
            (self.engine().gl().finish)();
            (self.engine().gl().begin_query)(gl::TIME_ELAPSED, rig.queries[span]);
        }
        let r = f(self);
        // SAFETY: as above; the query begun above.
        unsafe { (self.engine().gl().end_query)(gl::TIME_ELAPSED) };
        r
    }

    /// Each view's texture back to its content (untimed).
    fn restore_views(&mut self, rig: &GlRig) {
        let views: Vec<GlView> = rig
            .views
            .iter()
            .zip(&rig.pristine)
            .map(|(v, &p)| GlView { texture: p, ..*v })
            .collect();
        let back: Vec<u32> = rig.views.iter().map(|v| v.texture).collect();
        copy_views(self.engine().gl(), &views, &back);
    }

    fn destroy_rig(&mut self, rig: GlRig) {
        for t in rig
            .views
            .iter()
            .map(|v| v.texture)
            .chain(rig.pristine)
            .chain(rig.scratch)
        {
            self.delete_texture(t);
        }
        let g = self.engine().gl();
        // SAFETY: the context is current; names made here (0 is ignored by both calls).
        unsafe {
            (g.delete_buffers)(1, &rig.buffer);
            (g.delete_queries)(SPANS as i32, rig.queries.as_ptr());
        }
    }
}

/// Copies each view's region into the texture of the same index in `to` (glCopyImageSubData:
/// no conversion, the floor any path pays to touch the pixels once).
fn copy_views(g: &Gl, views: &[GlView], to: &[u32]) {
    for (v, &dst) in views.iter().zip(to) {
        let (x, y, w, h) = v.rect;
        // SAFETY: the context is current; both textures are 2D of the view's format and at
        // least its region's size (made by the rig).
        unsafe {
            (g.copy_image_sub_data)(
                v.texture,
                gl::TEXTURE_2D,
                0,
                x as i32,
                y as i32,
                0,
                dst,
                gl::TEXTURE_2D,
                0,
                0,
                0,
                0,
                w as i32,
                h as i32,
                1,
            )
        };
    }
}

/// The buffer path's copies alone: each view's region into `buffer` and back.
fn transfers(g: &Gl, views: &[GlView], buffer: u32) {
    for v in views {
        let format = GlFormat::of(v.internal_format).expect("the rig's format");
        let bytes = (v.rect.2 * v.rect.3 * format.pixel.bytes_per_pixel()) as usize;
        // SAFETY: the context is current; the buffer holds one region's texels; the pixel
        // store is at its defaults in the offline context; the bindings are the offline
        // context's own.
        unsafe {
            (g.bind_buffer)(gl::PIXEL_PACK_BUFFER, buffer);
            read_region(g, v, format, v.rect, (std::ptr::null_mut(), bytes));
            (g.bind_buffer)(gl::PIXEL_PACK_BUFFER, 0);
            (g.memory_barrier)(gl::PIXEL_BUFFER_BARRIER_BIT);
            (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, buffer);
            write_region(g, v, format, v.rect, std::ptr::null());
            (g.bind_buffer)(gl::PIXEL_UNPACK_BUFFER, 0);
        }
    }
}
