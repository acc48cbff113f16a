//! A session's enhancement: the GPU engine that does a frame's work (gpu/frame/frame_engine.rs), the
//! indicator's timer, and the session's start for the log. One call per frame into gpu/.

use super::indicator::{self, Timer};
use super::log;
use super::settings::Settings;
use crate::algorithm::params::Params;
use crate::blurred_texels::{BlurredTexels, TexelSink};
use crate::gpu::frame::OverlayPixels;
use crate::gpu::frame::{FrameBackground, FrameEngine, FrameOptions};
use crate::gpu::pipelines::BuildReport;
use crate::gpu::shaders::shader_ids::ShaderId;
use crate::gpu::{CapturedView, FrameView, GpuDevice, GpuError};
use crate::image::RgbaImage;
use std::sync::Arc;
use std::time::Instant;

pub struct Processor {
    engine: Option<FrameEngine>,
    /// When the in-headset indicator shows (set from the first enhanced frame on).
    indicator: Timer,
    /// When the session started (xrCreateSession).
    pub started: Instant,
}

impl Processor {
    /// Sets up the engine on the session's device; its pipelines start building at once on
    /// the engine's own thread, `first` first.
    pub fn new(gpu: GpuDevice, first: &[ShaderId]) -> Result<Processor, GpuError> {
        let started = Instant::now();
        let processor = Processor {
            engine: Some(FrameEngine::new(gpu, &[])?),
            indicator: Timer::default(),
            started,
        };
        // Through request: a warm-up device that cannot be made is said here.
        processor.request(first);
        Ok(processor)
    }

    fn engine(&self) -> &FrameEngine {
        self.engine.as_ref().expect("only taken in drop")
    }

    fn engine_mut(&mut self) -> &mut FrameEngine {
        self.engine.as_mut().expect("only taken in drop")
    }

    pub fn gpu(&self) -> &GpuDevice {
        &self.engine().gpu
    }

    /// Tells the pipeline thread to stop, without waiting: the session passes through from now
    /// on, and the processor is dropped only at xrDestroySession.
    pub fn stop_building(&self) {
        self.engine().stop_building();
    }

    /// Queues shaders to build ahead of earlier requests (at xrCreateSession, and when a
    /// swapchain's format becomes known). On the app's thread: a CPU driver's warm-up device
    /// is made here when one of them needs it, never on the pipeline thread (gpu/pipelines/warm_up.rs).
    pub fn request(&self, ids: &[ShaderId]) {
        let t = Instant::now();
        match self.engine().request(ids) {
            Some(Ok(())) => log::debug(&format!(
                "warm-up device made on the app's thread in {:.3} s",
                t.elapsed().as_secs_f64()
            )),
            Some(Err(e)) => log::info(&format!(
                "no warm-up device ({e}): shaders compile at their first dispatch; not tried again in this session"
            )),
            None => {}
        }
    }

    /// Whether live frames' prepared texels go straight into the images the views sample.
    pub fn direct_texels(&self) -> bool {
        self.engine().direct_texels()
    }

    /// Where the session's live source should write its frames' texels (gpu/texels/texel_slots.rs).
    pub fn texel_sink(&self) -> Arc<dyn TexelSink> {
        self.engine().texel_sink()
    }

    /// Whether a frame has sampled texels the source's thread wrote into a mapped image.
    pub fn texels_from_source(&self) -> bool {
        self.engine().texels_from_source().0 > 0
    }

    pub fn build_report(&self) -> Option<BuildReport> {
        self.engine().build_report()
    }

    /// An error when the GPU did not finish: the session must then stop using this processor.
    pub fn forget_swapchain(&mut self, swapchain: u64) -> Result<(), GpuError> {
        self.engine_mut().forget_swapchain(swapchain)
    }

    /// Enhances the views with the newest background, and draws the indicator while it shows.
    /// [`GpuError::Pending`] while a pipeline is still being built (frames pass through).
    pub fn process(
        &mut self,
        views: &[FrameView],
        background: FrameBackground,
        settings: &Settings,
        options: FrameOptions,
    ) -> Result<Vec<CapturedView>, GpuError> {
        let params: &Params = &settings.params;
        let engine = self.engine.as_mut().expect("only taken in drop");
        let ready = engine.pipelines_ready(views, params, options.wait_for_pipelines)?;
        // The indicator's time starts with the first enhanced frame, not while pipelines build.
        self.indicator.update(settings, Instant::now());
        let text = self.indicator.showing(Instant::now()).map(str::to_string);
        let runs = |region| {
            text.as_deref()
                .map_or(Vec::new(), |t| indicator::runs(t, region))
        };
        let overlay = text.as_deref().map(|key| OverlayPixels {
            key,
            colour: indicator::COLOUR,
            runs: &runs,
        });
        engine.process(ready, views, background, params, overlay.as_ref(), options)
    }
}

impl Drop for Processor {
    /// Runs on the app's thread (xrDestroySession, xrDestroyInstance, or a failed set-up).
    fn drop(&mut self) {
        if let Some(Err(e)) = self.engine.take().map(FrameEngine::finish) {
            log::info(&format!(
                "the GPU did not finish the layer's last work ({e}): its objects are left alive, not destroyed"
            ));
        }
    }
}

/// The background image of a frame (a new `sequence` is a new camera frame), with its texels
/// when its source prepared them.
pub fn background<'a>(
    image: &'a RgbaImage,
    prepared: Option<&'a BlurredTexels>,
    sequence: u64,
) -> FrameBackground<'a> {
    FrameBackground {
        image,
        prepared,
        sequence,
    }
}
