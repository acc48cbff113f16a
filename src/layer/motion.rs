//! Motion compensation at xrEndFrame: the camera frame's capture time as XrTime, the head (the
//! layer's VIEW space) located in LOCAL then, each projection view brought into LOCAL through
//! its layer's space at displayTime, and each view's mapping from the camera at capture to the
//! eye at display ([`crate::algorithm::reprojection`]). Also answers the `world:` source's
//! questions for head poses, and keeps what captures record of each view.

use super::app_spaces;
use super::dispatch::NextFns;
use super::live_settings::Settings;
use super::log;
pub use super::session_motion::{camera_config, SessionMotion, ViewRecord};
use super::spaces::{self, Spaces};
use super::state::SessionState;
use super::view_mappings::{self, Source, ViewGeometry};
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::registration::{view_mapping, Pose};
use crate::algorithm::reprojection::view_in_world;
use crate::camera::clock;
use openxr_sys as xr;
use std::time::Instant;

/// A live frame older than this (a camera that stalled) is no capture of the moment either.
const STILL_AFTER: std::time::Duration = std::time::Duration::from_secs(5);

/// What one xrEndFrame knows about motion.
pub struct FrameMotion {
    next: NextFns,
    spaces: Option<Spaces>,
    display_time: xr::Time,
    camera_time: Option<xr::Time>,
    /// The head at the camera's capture time, in LOCAL.
    head: Option<Pose>,
    compensation: bool,
    records: Vec<ViewRecord>,
}

/// Answers the `world:` source, then locates the head at the capture time of the camera frame
/// about to be used (`captured_at`, None for a still image), corrected by `camera_latency_ms`.
pub fn at_end_frame(
    s: &mut SessionState,
    display_time: xr::Time,
    captured_at: Option<Instant>,
) -> FrameMotion {
    s.motion.measure_offset(display_time);
    let (next, spaces, instance) = (s.next, s.motion.spaces, s.instance);
    for t in s.motion.poses.wanted() {
        let pose = spaces.and_then(|sp| {
            let time = s.motion.xr_time(instance, t)?;
            spaces::locate(&next, sp.view, sp.local, time)
        });
        s.motion.poses.record(t, pose);
    }
    let latency_ns = (f64::from(s.settings.motion.camera_latency_ms) * 1e6) as i64;
    // A still image, or a frame long stalled, is not a capture of the moment: it stays head-fixed.
    let captured_at = captured_at.filter(|t| t.elapsed() < STILL_AFTER);
    let camera_time = captured_at.and_then(|t| {
        s.motion
            .xr_time(instance, clock::monotonic_ns(t) - latency_ns)
    });
    let head = spaces
        .zip(camera_time)
        .and_then(|(sp, t)| spaces::locate(&next, sp.view, sp.local, t));
    let compensation =
        s.settings.motion.compensation && s.settings.registration.profile().is_some();
    let still = s
        .frame_in_use
        .as_ref()
        .is_some_and(|f| f.captured_at.is_none());
    if compensation && still {
        log::once("still-head-fixed", "the background is a still image (image: or color:): it stays head-fixed; motion compensation applies to live sources (camera, video, world:)");
    }
    if compensation && captured_at.is_some() && head.is_none() && spaces.is_some() {
        log::once("head-not-located", "the head could not be located at a camera frame's capture time (tracking lost or time out of range): that frame's background is head-fixed");
    }
    FrameMotion {
        next,
        spaces,
        display_time,
        camera_time,
        head,
        compensation,
        records: Vec::new(),
    }
}

impl FrameMotion {
    /// The mappings of one projection layer's views (poses in `space` at displayTime).
    pub fn mappings(
        &mut self,
        settings: &Settings,
        views: &[ViewGeometry],
        space: xr::Space,
    ) -> Vec<(CameraMapping, Source)> {
        let fixed = view_mappings::projection_mappings(settings, views);
        let layer = self
            .spaces
            .and_then(|sp| spaces::locate(&self.next, space, sp.local, self.display_time));
        let space_type = app_spaces::type_name(space);
        for view in views {
            self.records.push(ViewRecord {
                display_time: self.display_time.as_nanos(),
                view: *view,
                space_type: space_type.clone(),
                camera_time: self.camera_time.map(|t| t.as_nanos()),
                camera_pose: layer.zip(self.head).map(|(l, h)| l.inverse().then(&h)),
            });
        }
        let (Some(layer), Some(head), Some(profile)) =
            (layer, self.head, settings.registration.profile())
        else {
            return fixed;
        };
        if !self.compensation {
            return fixed;
        }
        views
            .iter()
            .zip(fixed)
            .enumerate()
            .map(|(eye, (view, fixed))| {
                if fixed.1 != Source::Profile {
                    return fixed;
                }
                let at_display = view_in_world(&layer, &view.pose);
                match view_mapping(&view.fov, &at_display, &head, &profile) {
                    Ok(m) => (settings.registration.nudge(eye).apply(&m), Source::Profile),
                    Err(_) => fixed,
                }
            })
            .collect()
    }

    /// Keeps this frame's view records for captures.
    pub fn finish(self, s: &mut SessionState) {
        s.motion.views = self.records;
    }
}

fn pose_json(p: &Pose) -> serde_json::Value {
    let (o, q) = (p.position, p.orientation);
    serde_json::json!({"position": [o.x, o.y, o.z], "orientation": [q.x, q.y, q.z, q.w]})
}

/// The capture JSON's fields for one view (all null when the frame's views are not known).
pub fn capture_json(record: Option<&ViewRecord>) -> serde_json::Map<String, serde_json::Value> {
    let null = serde_json::Value::Null;
    let json = match record {
        Some(r) => {
            let f = r.view.fov;
            serde_json::json!({
                "display_time": r.display_time,
                "view_pose": pose_json(&r.view.pose),
                "view_fov": {
                    "angle_left": f.angle_left,
                    "angle_right": f.angle_right,
                    "angle_up": f.angle_up,
                    "angle_down": f.angle_down,
                },
                "space_type": r.space_type,
                "camera_time": r.camera_time,
                "camera_pose": r.camera_pose.as_ref().map_or(null, pose_json),
            })
        }
        None => serde_json::json!({
            "display_time": null, "view_pose": null, "view_fov": null,
            "space_type": null, "camera_time": null, "camera_pose": null,
        }),
    };
    match json {
        serde_json::Value::Object(map) => map,
        _ => serde_json::Map::new(),
    }
}
