//! What the layer tracks per instance, session and swapchain, keyed by raw handle.
//!
//! Lock order, everywhere: a session, then its swapchains (one at a time), then the registry.
//! The registry lock is held only for map operations (look up, insert, remove, clone out the
//! `Arc`s), never while taking another lock. Code that starts from a swapchain handle and needs
//! its session reads the session handle, drops the swapchain lock, and locks the session first
//! (`swapchain::with_session`). No lock is held across a runtime call that may block
//! (xrWaitSwapchainImage, xrEndFrame), so a render thread and the frame thread never wait on
//! each other through the layer.

use super::dispatch::NextFns;
use super::graphics::SessionGraphics;
use super::image_states::ImageStates;
use super::indicator::Timer;
use super::live_settings::Settings;
use super::log;
use crate::gpu::PixelFormat;
use openxr_sys as xr;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

pub struct InstanceState {
    pub next: NextFns,
    pub settings: Arc<Settings>,
    /// CLOCK_MONOTONIC to XrTime (None: the instance was created before the layer could ask).
    pub timespec: Option<super::timespec::Timespec>,
}

/// What the log says, after why, when a session stops being enhanced.
pub const PASSING_THROUGH: &str = "passing this session's frames through from now on";

pub struct SessionState {
    pub handle: xr::Session,
    pub instance: xr::Instance,
    pub next: NextFns,
    pub settings: Arc<Settings>,
    /// The session's graphics, which do the frame's work on the app's device or context.
    /// None: this session passes through (an API the layer does not enhance, set-up failed,
    /// or an earlier failure).
    pub graphics: Option<Box<dyn SessionGraphics>>,
    /// Engines of earlier failures, kept until xrDestroySession: ending one waits for its
    /// pipeline thread, which no frame call may do.
    pub retired: Vec<Box<dyn SessionGraphics>>,
    /// When the in-headset indicator shows (set from the first enhanced frame on).
    pub indicator: Timer,
    /// When the session started (xrCreateSession), for the log's line on when enhancement
    /// began.
    pub started: Instant,
    /// The running background source (camera, video, image): open only while the session's
    /// frames are enhanced (opened at the first frame the layer acts on).
    pub background: Option<crate::camera::Background>,
    /// The background was asked for (opened, being opened, or failed to open).
    pub background_requested: bool,
    /// The background's last frame request got a frame (a None after it is a loss).
    pub background_delivered: bool,
    /// Since when the layer has not acted on a frame (the background closes after a while).
    pub idle_since: Option<std::time::Instant>,
    /// Frames submitted through xrEndFrame so far.
    pub frames: u64,
    /// Frames the layer processed (captures are numbered by this).
    pub processed: u64,
    /// The blend mode of the last xrEndFrame (None before the first).
    pub last_blend_mode: Option<xr::EnvironmentBlendMode>,
    /// Whether any xrEndFrame has named sub-images yet (before that, a swapchain's view
    /// regions are unknown).
    pub regions_seen: bool,
    /// The layer's spaces, clock conversion and head poses for motion compensation.
    pub motion: super::session_motion::SessionMotion,
    /// The background frame this xrEndFrame's mappings were computed for.
    pub frame_in_use: Option<crate::camera::Frame>,
    /// Frames passed through while the graphics could not be reached, and when to try again.
    pub retry: super::frame_retry::FrameRetry,
    /// The GPU time of the layer's work per enhanced frame, for the log.
    pub gpu_time: super::gpu_time::GpuTimeLog,
}

impl SessionState {
    /// The one way a session turns pass-through: the log says why, once ("{why}: passing this
    /// session's frames through from now on"), and the engine retires. Its pipeline thread is
    /// told to stop, and the engine is kept until xrDestroySession, so that no call of the app
    /// waits here for a shader compile, a device teardown or a cache write. A session already
    /// passing through says nothing more (a failure that repeats each frame is one line).
    pub fn pass_through(&mut self, why: &str) {
        if let Some(engine) = self.graphics.take() {
            log::info(&format!("{why}: {PASSING_THROUGH}"));
            engine.stop_building();
            self.retired.push(engine);
        }
        // Its mapped images stay valid until it is ended, but no frame samples them now.
        if let Some(bg) = &self.background {
            bg.deliver_texels_to(None);
        }
    }

    /// Ends the session's engines, the current one first: each waits for its last work and
    /// its pipeline thread, then destroys what it made. On the app's thread, inside
    /// xrDestroySession or xrDestroyInstance.
    pub fn end_engines(&mut self) {
        if let Some(line) = std::mem::take(&mut self.gpu_time).session_line() {
            log::info(&line);
        }
        for engine in self
            .graphics
            .take()
            .into_iter()
            .chain(self.retired.drain(..))
        {
            if let Err(e) = engine.finish() {
                log::info(&e);
            }
        }
    }
}

/// One view's region of a swapchain image, as a composition layer names it.
#[derive(Clone, Copy, Debug)]
pub struct ViewRegion {
    pub rect: xr::Rect2Di,
    pub array_index: u32,
    /// A projection view's camera mapping, registered from its field of view and pose at the
    /// frame's xrEndFrame (None for quad layers, and for the whole-image regions used before the
    /// first xrEndFrame: they take the manual mapping).
    pub mapping: Option<crate::algorithm::mapping::CameraMapping>,
    /// A projection view's pixels per degree, from its field of view and width (None where
    /// `mapping` is).
    pub pixels_per_degree: Option<f64>,
}

#[derive(Clone, Debug)]
pub struct SwapchainInfo {
    /// The format as the app named it (a VkFormat, a GL internal format).
    pub api_format: i64,
    /// None for formats the engine does not handle (and for depth).
    pub pixel: Option<PixelFormat>,
    pub width: u32,
    pub height: u32,
    pub array_size: u32,
    /// The swapchain has the usage the session's graphics need to touch its images.
    pub usage_granted: bool,
    /// The layer also got storage usage (and, for sRGB, mutable format): views of this
    /// swapchain are enhanced in place.
    pub in_place: bool,
    /// The app made it with colour-attachment usage: the image-copy path may draw its tiles
    /// back into it (`copy_back = "tiles"`).
    pub attachment: bool,
    /// The app made it with sampled usage, or the layer added it (`copy_in = "sampled"`): the
    /// image-copy path may read it through a sampled view.
    pub sampled: bool,
}

impl SwapchainInfo {
    /// A swapchain's info from the app's create info (its format and size), the pixel format
    /// the engine handles it as (None: not handled) and the usage the layer got.
    pub fn new(
        app_info: &xr::SwapchainCreateInfo,
        pixel: Option<PixelFormat>,
        usage_granted: bool,
        in_place: bool,
    ) -> Self {
        SwapchainInfo {
            api_format: app_info.format,
            pixel,
            width: app_info.width,
            height: app_info.height,
            array_size: app_info.array_size,
            usage_granted,
            in_place,
            attachment: app_info
                .usage_flags
                .contains(xr::SwapchainUsageFlags::COLOR_ATTACHMENT),
            sampled: app_info
                .usage_flags
                .contains(xr::SwapchainUsageFlags::SAMPLED),
        }
    }

    /// Whether the layer may touch this swapchain's images at all.
    pub fn processable(&self) -> bool {
        self.pixel.is_some() && self.usage_granted
    }
}

pub struct SwapchainState {
    pub session: xr::Session,
    pub next: NextFns,
    pub info: SwapchainInfo,
    /// The swapchain's images (VkImages, GL texture names), once the app enumerated them.
    images: Vec<u64>,
    /// The images' states as the runtime sees them, and the release the layer holds.
    pub states: ImageStates,
    /// The regions the app's last xrEndFrame named in this swapchain (enhanced layers only):
    /// what an image released ahead of its xrEndFrame is enhanced with.
    pub last_views: Vec<ViewRegion>,
}

impl SwapchainState {
    /// A swapchain just created: no images enumerated, none held, no regions named yet.
    pub fn new(session: xr::Session, next: NextFns, info: SwapchainInfo) -> Self {
        SwapchainState {
            session,
            next,
            info,
            images: Vec::new(),
            states: ImageStates::default(),
            last_views: Vec::new(),
        }
    }

    /// The image at `index` of the swapchain, if the app enumerated that many.
    pub fn image(&self, index: usize) -> Option<u64> {
        self.images.get(index).copied()
    }

    /// Whether the app enumerated the swapchain's images.
    pub fn has_images(&self) -> bool {
        !self.images.is_empty()
    }

    /// The swapchain's images, as the app enumerated them.
    pub fn set_images(&mut self, images: Vec<u64>) {
        self.images = images;
    }
}

#[derive(Default)]
pub struct Registry {
    pub instances: HashMap<u64, Arc<InstanceState>>,
    pub sessions: HashMap<u64, Arc<Mutex<SessionState>>>,
    pub swapchains: HashMap<u64, Arc<Mutex<SwapchainState>>>,
}

pub fn registry() -> std::sync::MutexGuard<'static, Registry> {
    static REGISTRY: OnceLock<Mutex<Registry>> = OnceLock::new();
    let m = REGISTRY.get_or_init(|| Mutex::new(Registry::default()));
    // A panic while holding the lock leaves plain maps behind: keep using them.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

pub fn instance(handle: xr::Instance) -> Option<Arc<InstanceState>> {
    registry().instances.get(&handle.into_raw()).cloned()
}

pub fn session(handle: xr::Session) -> Option<Arc<Mutex<SessionState>>> {
    registry().sessions.get(&handle.into_raw()).cloned()
}

pub fn swapchain(handle: xr::Swapchain) -> Option<Arc<Mutex<SwapchainState>>> {
    registry().swapchains.get(&handle.into_raw()).cloned()
}

/// Locks a state mutex even if a panic poisoned it (the layer then passes through anyway).
pub fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}
