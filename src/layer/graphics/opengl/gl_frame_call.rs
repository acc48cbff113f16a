//! One frame call's work in the app's OpenGL context: the views as the GL engine names them,
//! the background's texels, the enhancement, the indicator drawn over it and, for a capture,
//! each view read back before and after. [`super::gl_session`] runs it inside the app's context.

use crate::algorithm::params::Params;
use crate::gpu::core::blurred_texels::{BlurTaps, BlurredTexels};
use crate::gpu::core::{overlay_pixel, BackgroundInput, OverlayPixels};
use crate::gpu::opengl::{GlError, GlFrameRunner, GlTarget, GlView, Outcome};
use crate::layer::graphics::session_graphics::{CapturedImage, NotDone, ViewImage};
use crate::layer::log;
use std::time::{Duration, Instant};

/// A frame call past this long is told in the debug log.
const SLOW_FRAME: Duration = Duration::from_millis(100);

/// A GL error as the layer takes it: an app binding the engine could not put back passes
/// only this frame through; anything else, the session.
pub(super) fn failed(e: GlError) -> NotDone {
    match e {
        GlError::Unrestorable(_) => NotDone::Skipped(e.to_string()),
        e => NotDone::Failed(e.to_string()),
    }
}

/// A view as the GL engine takes it.
pub(super) fn gl_view(v: &ViewImage) -> GlView {
    let (x, y) = v.key.offset;
    let (w, h) = v.key.extent;
    GlView {
        texture: v.image as u32,
        target: match v.layered {
            true => GlTarget::Texture2DArray {
                layer: v.key.array_index,
            },
            false => GlTarget::Texture2D,
        },
        internal_format: v.api_format as u32,
        // An OpenXR imageRect of an OpenGL swapchain counts rows from the bottom, as GL does.
        rect: (x as u32, y as u32, w, h),
        mapping: v.mapping,
        pixels_per_degree: v.pixels_per_degree,
    }
}

/// The background's texels for this frame: its source's, when made for these settings, else
/// prepared here once per background sequence.
fn texels<'a>(
    background: &'a BackgroundInput,
    prepared_here: &'a mut Option<(u64, BlurredTexels)>,
    params: &Params,
) -> &'a BlurredTexels {
    let size = (background.image.width, background.image.height);
    if let Some(t) = background.prepared.filter(|t| t.made_for(size, params)) {
        return t;
    }
    if prepared_here.as_ref().map(|(s, _)| *s) != Some(background.sequence) {
        let t = BlurredTexels::prepare_once(background.image, BlurTaps::of(params));
        *prepared_here = Some((background.sequence, t));
    }
    &prepared_here.as_ref().expect("set above").1
}

/// A frame's views, and what they are enhanced with.
pub(super) struct Frame<'a> {
    pub views: &'a [ViewImage],
    /// The same views as the engine takes them.
    pub gl_views: &'a [GlView],
    pub background: &'a BackgroundInput<'a>,
    pub params: &'a Params,
}

impl Frame<'_> {
    /// Enhances the views with the background, draws `overlay` over them, and with `capture`
    /// reads each back before and after.
    ///
    /// # Safety
    /// The app's context is current on this thread, and the layer holds the views' images
    /// (their release), so nothing else writes them during the call.
    pub unsafe fn enhance(
        &self,
        engine: &mut GlFrameRunner,
        prepared_here: &mut Option<(u64, BlurredTexels)>,
        overlay: Option<&OverlayPixels>,
        capture: bool,
    ) -> Result<Vec<CapturedImage>, NotDone> {
        let t = texels(self.background, prepared_here, self.params);
        // SAFETY: the caller's contract: the app's context is current.
        unsafe { engine.frame_started() };
        let started = Instant::now();
        let mappings: Vec<_> = self.gl_views.iter().map(|v| v.mapping).collect();
        // SAFETY: the caller's contract: the app's context is current.
        unsafe { engine.set_background_for(t, &mappings) }.map_err(failed)?;
        let uploaded = started.elapsed();
        let before = match capture {
            true => self.read(engine)?,
            false => Vec::new(),
        };
        // SAFETY: the caller's contract: the context is current, the images are the layer's.
        match unsafe { engine.enhance(self.gl_views, self.params) }.map_err(failed)? {
            Outcome::Compiling => return Err(NotDone::Pending),
            Outcome::Enhanced => {}
        }
        log_slow(started.elapsed(), uploaded);
        if let Some(o) = overlay {
            // SAFETY: as for the enhancement above.
            unsafe { self.draw_overlay(engine, o) }?;
        }
        // SAFETY: as for `frame_started` above.
        unsafe { engine.frame_ended() };
        if !capture {
            return Ok(Vec::new());
        }
        let after = self.read(engine)?;
        Ok(self.captured(before, after, engine.last_in_place()))
    }

    /// Each view's bytes as they are now (inside the caller's `enhance`).
    fn read(&self, engine: &GlFrameRunner) -> Result<Vec<Vec<u8>>, NotDone> {
        self.gl_views
            .iter()
            // SAFETY: inside `enhance`: the context is current; the view names a swapchain
            // texture.
            .map(|v| unsafe { engine.read_view(v) }.map_err(failed))
            .collect()
    }

    /// Draws the indicator's runs over each view.
    ///
    /// # Safety
    /// As [`Frame::enhance`].
    unsafe fn draw_overlay(
        &self,
        engine: &mut GlFrameRunner,
        o: &OverlayPixels,
    ) -> Result<(), NotDone> {
        for (v, g) in self.views.iter().zip(self.gl_views) {
            let runs = (o.runs)(v.key.extent);
            let pixel = overlay_pixel(v.format, o.colour);
            // SAFETY: the caller's contract.
            unsafe { engine.draw_runs(g, &runs, &pixel) }.map_err(failed)?;
        }
        Ok(())
    }

    /// The captures of the views, with the path each took (`stored`: enhanced in place).
    fn captured(
        &self,
        before: Vec<Vec<u8>>,
        after: Vec<Vec<u8>>,
        stored: &[bool],
    ) -> Vec<CapturedImage> {
        self.views
            .iter()
            .zip(before.into_iter().zip(after))
            .enumerate()
            .map(|(k, (v, (display, output)))| CapturedImage {
                path: match stored.get(k) {
                    Some(true) => "in-place",
                    _ => "copy",
                },
                view: v.clone(),
                display,
                output,
            })
            .collect()
    }
}

/// A frame call past SLOW_FRAME is told in the debug log: a driver that compiles a program's
/// code at its first dispatch does it in the enhancement.
fn log_slow(took: Duration, uploaded: Duration) {
    if took > SLOW_FRAME {
        log::debug(&format!(
            "an OpenGL frame call took {:.0} ms (background upload {:.0} ms)",
            took.as_secs_f64() * 1e3,
            uploaded.as_secs_f64() * 1e3
        ));
    }
}
