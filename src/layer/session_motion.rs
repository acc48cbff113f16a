//! A session's motion state: the layer's own VIEW and LOCAL spaces, the clock conversion, the
//! head poses a `world:` source asks for, and what captures record of each view. The work at
//! xrEndFrame is in [`super::motion`].

use super::dispatch::NextFns;
use super::live_settings::Settings;
use super::log;
use super::spaces::{self, Spaces};
use super::timespec::Timespec;
use super::view_mappings::ViewGeometry;
use crate::algorithm::registration::Pose;
use crate::camera::{clock, CaptureConfig, HeadPoses, WorldRig};
use openxr_sys as xr;
use std::sync::Arc;

/// A session's motion state.
#[derive(Default)]
pub struct SessionMotion {
    pub(super) spaces: Option<Spaces>,
    pub(super) timespec: Option<Timespec>,
    /// Without the timespec extension: the smallest displayTime - CLOCK_MONOTONIC seen.
    pub(super) offset_ns: Option<i64>,
    /// Where a `world:` source asks for head poses.
    pub poses: Arc<HeadPoses>,
    /// The last enhanced frame's views, as captures record them.
    pub views: Vec<ViewRecord>,
}

/// One projection view of a frame, as the capture JSON records it.
#[derive(Clone, Debug)]
pub struct ViewRecord {
    pub display_time: i64,
    pub view: ViewGeometry,
    pub space_type: Option<String>,
    pub camera_time: Option<i64>,
    /// The head at `camera_time` in the projection layer's space.
    pub camera_pose: Option<Pose>,
}

impl SessionMotion {
    /// Creates the session's spaces (on the app's thread, in xrCreateSession).
    pub fn create(next: &NextFns, session: xr::Session, timespec: Option<Timespec>) -> Self {
        SessionMotion {
            spaces: spaces::create(next, session),
            timespec,
            ..Default::default()
        }
    }

    /// Destroys the session's spaces (in xrDestroySession, before it is forwarded).
    pub fn destroy(&mut self, next: &NextFns) {
        if let Some(s) = self.spaces.take() {
            spaces::destroy(next, s);
        }
    }

    pub(super) fn xr_time(&self, instance: xr::Instance, ns: i64) -> Option<xr::Time> {
        match self.timespec.filter(Timespec::available) {
            Some(t) => t.xr_time(instance, ns),
            None => self.offset_ns.map(|o| xr::Time::from_nanos(ns + o)),
        }
    }

    pub(super) fn measure_offset(&mut self, display_time: xr::Time) {
        if self.timespec.is_some_and(|t| t.available()) {
            return;
        }
        log::once("no-timespec", "the runtime cannot convert CLOCK_MONOTONIC to XrTime (no XR_KHR_convert_timespec_time): camera times are mapped through the clocks' offset measured from displayTime");
        let offset = display_time.as_nanos() - clock::monotonic_now_ns();
        self.offset_ns = Some(self.offset_ns.map_or(offset, |o| o.min(offset)));
    }
}

/// The camera settings to open a source with: a `world:` source gets the camera profile and
/// this session's head poses.
pub fn camera_config(settings: &Settings, motion: &SessionMotion) -> CaptureConfig {
    let mut camera = settings.camera.clone();
    // A still background is prepared as it loads, with the blur in force then.
    camera.still_blur = Some(crate::gpu::core::blurred_texels::BlurTaps::of(
        &settings.params,
    ));
    camera.world = settings.registration.profile().map(|profile| WorldRig {
        profile,
        poses: motion.poses.clone(),
    });
    camera
}
