//! The running background source the consumer holds.

use crate::camera::error::CameraError;
use crate::camera::files::{color_frame, image_frame, open_video, play};
use crate::camera::mailbox::{Frame, Shared, SourceStatus};
use crate::camera::source::{CaptureConfig, SourceSpec};
use crate::camera::v4l2;
use crate::gpu::core::blurred_texels::{BlurTaps, TexelSink};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// An open background source. Dropping it asks the capture thread to stop without waiting for
/// it (drops happen inside the app's frame calls): the thread closes the device on its own
/// within a poll slice. `close` also waits for that.
pub struct Background {
    source: Source,
    description: String,
}

enum Source {
    Static(Frame),
    Threaded {
        shared: Arc<Shared>,
        thread: Option<JoinHandle<()>>,
        /// Cameras are watched for stalls and loss; videos only play.
        supervised: bool,
        stall_timeout: Duration,
        grace: Duration,
    },
}

impl Background {
    pub fn open(spec: &SourceSpec, cfg: &CaptureConfig) -> Result<Self, CameraError> {
        crate::fault::check("camera-open").map_err(CameraError::Device)?;
        let (source, description) = match spec {
            SourceSpec::Image(path) => (
                Source::Static(image_frame(path, cfg)?),
                format!("image {}", path.display()),
            ),
            SourceSpec::Color(c) => {
                let text = format!("colour #{:02X}{:02X}{:02X}", c[0], c[1], c[2]);
                (Source::Static(color_frame(*c, cfg)), text)
            }
            SourceSpec::Video(path) => {
                let (frames, fps) = open_video(path, cfg)?;
                let count = frames.count();
                let shared = Arc::new(Shared::new());
                let (thread_shared, smoothing) = (shared.clone(), cfg.smoothing);
                let start = Instant::now();
                let thread = std::thread::Builder::new()
                    .name("contrastxr-video".into())
                    .spawn(move || {
                        super::priority::yield_to_the_app();
                        play(frames, fps, start, &thread_shared, smoothing)
                    })
                    .map_err(|e| {
                        CameraError::File(format!("cannot start the video thread: {e}"))
                    })?;
                let text = format!("video {} ({count} frames at {fps:.2} fps)", path.display());
                (threaded(shared, thread, false, cfg), text)
            }
            SourceSpec::World(path) => {
                let (shared, thread, text) = super::world::spawn(path, cfg)?;
                (threaded(shared, thread, false, cfg), text)
            }
            SourceSpec::V4l2Device(_) | SourceSpec::V4l2Auto => {
                let (shared, thread, text) = v4l2::spawn(spec, cfg)?;
                (threaded(shared, thread, true, cfg), text)
            }
        };
        Ok(Background {
            source,
            description,
        })
    }

    /// The newest frame, without waiting; `None` before the first frame and once `Lost`.
    pub fn latest(&self) -> Option<Frame> {
        crate::fault::check("camera-loss").ok()?;
        match &self.source {
            Source::Static(frame) => Some(frame.clone()),
            Source::Threaded { shared, .. } => {
                shared.mark_used();
                match self.status() {
                    SourceStatus::Lost => None,
                    _ => shared.peek(),
                }
            }
        }
    }

    /// Asks a live source to prepare each new frame with `blur` on its own thread
    /// (`Frame::prepared`), off the consumer's frame calls. Static sources are prepared once
    /// by the consumer: nothing to do.
    pub fn prepare_with(&self, blur: BlurTaps) {
        if let Source::Threaded { shared, .. } = &self.source {
            shared.want(blur);
        }
    }

    /// Makes a live source write each new frame's prepared texels into `sink` (None: stop), on
    /// its own thread before the frame is published. Static sources have no thread: nothing to do.
    pub fn deliver_texels_to(&self, sink: Option<Arc<dyn TexelSink>>) {
        if let Source::Threaded { shared, .. } = &self.source {
            shared.deliver_to(sink);
        }
    }

    pub fn status(&self) -> SourceStatus {
        match &self.source {
            Source::Static(_) => SourceStatus::Live,
            Source::Threaded {
                shared,
                supervised: true,
                stall_timeout,
                grace,
                ..
            } => shared.status(Instant::now(), *stall_timeout, *grace),
            Source::Threaded { shared, .. } => {
                // A video is live once its first frame is decoded (open decodes frame 0 first).
                match shared.peek() {
                    Some(_) => SourceStatus::Live,
                    None => SourceStatus::Waiting {
                        since: Instant::now(),
                    },
                }
            }
        }
    }

    /// What was opened, e.g. `/dev/video0 (HD Webcam) 640x480 YUYV at 30 fps`.
    pub fn description(&self) -> &str {
        &self.description
    }
}

fn threaded(
    shared: Arc<Shared>,
    thread: JoinHandle<()>,
    supervised: bool,
    cfg: &CaptureConfig,
) -> Source {
    Source::Threaded {
        shared,
        thread: Some(thread),
        supervised,
        stall_timeout: cfg.stall_timeout,
        grace: cfg.grace,
    }
}

impl Background {
    /// Stops the source and waits until its thread has ended (the device is closed).
    pub fn close(mut self) {
        if let Some(thread) = self.stop() {
            let _ = thread.join();
        }
    }

    /// Stops a live source and waits at most `bound` for its thread to end (a camera's
    /// controls restored, its device closed). False when the thread still runs then: it ends
    /// on its own.
    pub fn close_within(mut self, bound: Duration) -> bool {
        let Some(thread) = self.stop() else {
            return true;
        };
        let deadline = Instant::now() + bound;
        while !thread.is_finished() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(2));
        }
        thread.is_finished() && thread.join().is_ok()
    }

    fn stop(&mut self) -> Option<JoinHandle<()>> {
        let Source::Threaded { shared, thread, .. } = &mut self.source else {
            return None;
        };
        shared.stop.store(true, Ordering::Release);
        let thread = thread.take()?;
        thread.thread().unpark();
        Some(thread)
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        // The handle is let go: the thread ends on its own.
        drop(self.stop());
    }
}
