//! A session's graphics for tests, with no device at all: it records what the layer asks of it
//! and answers each frame as the test says, so the layer's own logic (pass-through, held
//! releases, retired engines) is tested without a GPU. Built only for tests.

use super::session_graphics::{CapturedImage, NotDone, SessionGraphics, ViewImage};
use crate::algorithm::params::Params;
use crate::gpu::core::{BackgroundInput, OverlayPixels};
use crate::gpu::PixelFormat;
use crate::layer::live_settings::Settings;
use openxr_sys as xr;
use std::sync::{Arc, Mutex, MutexGuard};

/// The fake's swapchain format: any format the app names is read as sRGB RGBA8.
pub const FORMAT: PixelFormat = PixelFormat::SRGB8;

/// How the fake answers a frame's `enhance`.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// The views are enhanced.
    Enhance,
    /// Shaders are still being built: the frame passes through.
    Pending,
    /// The engine fails for good, for this reason.
    Fail(String),
    /// What the frame needs cannot be reached now, for this reason.
    Unreachable(String),
    /// The engine's code panics.
    Panic,
}

/// What the layer asked of the fake, for the test to read.
#[derive(Debug, Default)]
pub struct Calls {
    /// The views of each `enhance` call, by key swapchain.
    pub enhanced: Vec<Vec<u64>>,
    pub requested_shaders: u32,
    pub stopped_building: u32,
    pub finished: u32,
}

/// Locks a fake's record even after a failed assertion poisoned it (the rig's drop still
/// ends the session).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The test's side of a fake: sets its answers and reads its calls.
#[derive(Clone)]
pub struct Handle {
    outcome: Arc<Mutex<Outcome>>,
    forget_fails: Arc<Mutex<bool>>,
    calls: Arc<Mutex<Calls>>,
}

impl Handle {
    /// The fake's answer to every following frame.
    pub fn answer(&self, outcome: Outcome) {
        *lock(&self.outcome) = outcome;
    }

    /// Whether the fake fails to forget a swapchain (its objects cannot be released).
    pub fn fail_forget(&self) {
        *lock(&self.forget_fails) = true;
    }

    pub fn calls(&self) -> MutexGuard<'_, Calls> {
        lock(&self.calls)
    }
}

/// A session's graphics that touch nothing.
pub struct FakeGraphics {
    handle: Handle,
}

impl FakeGraphics {
    /// A fake that enhances every frame, and the test's handle to it.
    pub fn boxed() -> (Box<dyn SessionGraphics>, Handle) {
        let handle = Handle {
            outcome: Arc::new(Mutex::new(Outcome::Enhance)),
            forget_fails: Arc::default(),
            calls: Arc::default(),
        };
        let fake = FakeGraphics {
            handle: handle.clone(),
        };
        (Box::new(fake), handle)
    }

    fn outcome(&self) -> Outcome {
        lock(&self.handle.outcome).clone()
    }
}

impl SessionGraphics for FakeGraphics {
    fn api(&self) -> &'static str {
        "fake"
    }

    fn graphics(&self) -> &'static str {
        "fake"
    }

    fn pixel_format(&self, _api_format: i64) -> Option<PixelFormat> {
        Some(FORMAT)
    }

    fn format_name(&self, api_format: i64) -> String {
        format!("fake format {api_format}")
    }

    /// As Vulkan's copy path: usage the app's create info may lack, so the layer asks for it.
    fn needed_usage(&self) -> xr::SwapchainUsageFlags {
        xr::SwapchainUsageFlags::TRANSFER_SRC | xr::SwapchainUsageFlags::TRANSFER_DST
    }

    fn in_place_usage(
        &self,
        _format: PixelFormat,
        _info: &xr::SwapchainCreateInfo,
        _settings: &Settings,
    ) -> Option<xr::SwapchainUsageFlags> {
        None
    }

    unsafe fn images(
        &self,
        _images: *const xr::SwapchainImageBaseHeader,
        _count: usize,
    ) -> Option<Vec<u64>> {
        None
    }

    fn request_shaders(&mut self, _: &Params, _: PixelFormat, _: u32, _: bool, _: bool) {
        self.handle.calls().requested_shaders += 1;
        if self.outcome() == Outcome::Panic {
            panic!("the fake graphics panic while requesting shaders");
        }
    }

    fn take_gpu_times(&mut self) -> Vec<std::time::Duration> {
        Vec::new()
    }

    fn forget_swapchain(&mut self, _swapchain: u64) -> Result<(), String> {
        match *lock(&self.handle.forget_fails) {
            true => Err("the fake graphics cannot release the swapchain's views".into()),
            false => Ok(()),
        }
    }

    fn take_live_texels(&self, _background: &crate::camera::Background) {}

    fn ready(&mut self, _: &[ViewImage], _: &Params, _wait: bool) -> Result<(), NotDone> {
        match self.outcome() {
            Outcome::Pending => Err(NotDone::Pending),
            _ => Ok(()),
        }
    }

    fn enhance(
        &mut self,
        views: &[ViewImage],
        _background: BackgroundInput,
        _params: &Params,
        _overlay: Option<&OverlayPixels>,
        _capture: bool,
    ) -> Result<Vec<CapturedImage>, NotDone> {
        let keys = views.iter().map(|v| v.key.swapchain).collect();
        self.handle.calls().enhanced.push(keys);
        match self.outcome() {
            Outcome::Enhance => Ok(Vec::new()),
            Outcome::Pending => Err(NotDone::Pending),
            Outcome::Fail(why) => Err(NotDone::Failed(why)),
            Outcome::Unreachable(why) => Err(NotDone::Unreachable(why)),
            Outcome::Panic => panic!("the fake graphics panic while enhancing"),
        }
    }

    fn pending_line(&self) -> &'static str {
        "the fake graphics are building"
    }

    fn build_summary(&self) -> Option<String> {
        None
    }

    fn frame_lines(&self, _views: &[ViewImage], _prepared: bool) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    fn stop_building(&self) {
        self.handle.calls().stopped_building += 1;
    }

    fn finish(self: Box<Self>) -> Result<(), String> {
        self.handle.calls().finished += 1;
        Ok(())
    }
}
