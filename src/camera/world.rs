//! `world:PATH`: a simulated head-mounted camera in a world made of one equirectangular
//! panorama (fixed in the consumer's world space, OpenXR's LOCAL for the layer). At
//! `camera_fps` it captures: it asks for the head's pose at the capture time, renders the
//! camera profile's view of the panorama from there once the pose is known, and hands the frame
//! over `world_latency_ms` after its capture, stamped with its capture time, as a real camera's
//! frame would arrive. The panorama is at infinity: only the camera's orientation matters.
//!
//! The head's poses come from the consumer through [`HeadPoses`](crate::camera::rig::HeadPoses): this module never knows who
//! tracks the head. The consumer takes the [`HeadPoses::wanted`](crate::camera::rig::HeadPoses::wanted) times (CLOCK_MONOTONIC ns),
//! locates the head at each and [`HeadPoses::record`](crate::camera::rig::HeadPoses::record)s the answer.

use crate::algorithm::registration::{CameraProfile, Pose};
use crate::algorithm::reprojection::panorama_uv;
use crate::camera::clock::{instant_of_ns, monotonic_now_ns};
use crate::camera::error::CameraError;
use crate::camera::log_sink::log;
use crate::camera::mailbox::{Frame, Shared};
use crate::camera::rig::{HeadPoses, WorldRig};
use crate::camera::source::CaptureConfig;
use crate::image::RgbaImage;
use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;
use std::thread::JoinHandle;

/// A frame whose head pose is not known this long after it was due is dropped.
const POSE_WAIT_NS: i64 = 1_000_000_000;

/// Starts the simulated camera's thread.
pub(crate) fn spawn(
    path: &Path,
    cfg: &CaptureConfig,
) -> Result<(Arc<Shared>, JoinHandle<()>, String), CameraError> {
    let rig = cfg.world.clone().ok_or_else(|| {
        CameraError::File(
            "world: needs a camera profile (camera_fov or camera_intrinsics) and head tracking"
                .into(),
        )
    })?;
    let panorama = RgbaImage::load(path).map_err(|e| CameraError::File(format!("world:{e}")))?;
    let (width, height) = cfg.frame_size();
    let fps = cfg.fps.max(1);
    let latency_ns = (f64::from(cfg.world_latency_ms) * 1e6) as i64;
    let text = format!(
        "world {} ({}x{} panorama) seen by a simulated {width}x{height} camera at {fps} fps, delivered {} ms after capture",
        path.display(),
        panorama.width,
        panorama.height,
        cfg.world_latency_ms
    );
    let shared = Arc::new(Shared::new());
    let thread_shared = shared.clone();
    let camera = Camera {
        panorama,
        rig,
        size: (width, height),
        period_ns: 1_000_000_000 / i64::from(fps),
        latency_ns,
    };
    let thread = std::thread::Builder::new()
        .name("contrastxr-world".into())
        .spawn(move || {
            super::priority::yield_to_the_app();
            camera.run(&thread_shared)
        })
        .map_err(|e| CameraError::File(format!("cannot start the world thread: {e}")))?;
    Ok((shared, thread, text))
}

struct Camera {
    panorama: RgbaImage,
    rig: WorldRig,
    size: (u32, u32),
    period_ns: i64,
    latency_ns: i64,
}

impl Camera {
    fn run(self, shared: &Shared) {
        let mut next = monotonic_now_ns();
        let mut pending: VecDeque<i64> = VecDeque::new();
        let mut sequence = 0;
        let mut warned = false;
        while !shared.stopping() {
            let now = monotonic_now_ns();
            if now >= next {
                self.rig.poses.want(next);
                pending.push_back(next);
                // A late thread skips captures rather than bunching them.
                next = (next + self.period_ns).max(now);
            }
            let (newest, unlocated) =
                newest_due(&mut pending, now, self.latency_ns, &self.rig.poses);
            if unlocated && !warned {
                log("world: no head pose for a capture time: frame dropped");
                warned = true;
            }
            if let Some((t, head)) = newest {
                sequence += 1;
                shared.publish(Frame {
                    image: Arc::new(self.render(&head)),
                    sequence,
                    captured_at: Some(instant_of_ns(t)),
                    prepared: None,
                });
            }
            let due = pending
                .front()
                .map_or(next, |t| (t + self.latency_ns).min(next));
            let wake = due.clamp(now + 1_000_000, now + 20_000_000);
            shared.sleep_until(instant_of_ns(wake));
        }
    }

    fn render(&self, head: &Pose) -> RgbaImage {
        render(&self.panorama, &self.rig.profile, head, self.size)
    }
}

/// Takes the captures due by `now` (delivered `latency_ns` after their time) off `pending`,
/// and returns the newest whose head pose is known, and whether one was dropped for want of
/// a pose. Only the newest is rendered: a thread that fell behind (a loaded machine) delivers
/// the latest view, as a real camera's newest frame supersedes the ones before it, instead of
/// rendering each stale one in turn and falling further behind. A due capture whose pose may
/// still come stops the scan.
fn newest_due(
    pending: &mut VecDeque<i64>,
    now: i64,
    latency_ns: i64,
    poses: &HeadPoses,
) -> (Option<(i64, Pose)>, bool) {
    let (mut newest, mut unlocated) = (None, false);
    while let Some(&t) = pending.front() {
        if now < t + latency_ns {
            break;
        }
        match poses.take(t) {
            Some(Some(head)) => newest = Some((t, head)),
            Some(None) => {}
            None if now < t + latency_ns + POSE_WAIT_NS => break,
            None => unlocated = true,
        }
        pending.pop_front();
    }
    (newest, unlocated)
}

/// What a camera mounted as `profile` says on a head at `head` sees of the panorama.
pub fn render(
    panorama: &RgbaImage,
    profile: &CameraProfile,
    head: &Pose,
    (width, height): (u32, u32),
) -> RgbaImage {
    let turn = head.then(&profile.pose).orientation;
    let mut out = RgbaImage::new(width, height, [0, 0, 0, 255]);
    out.has_alpha = false;
    for y in 0..height {
        for x in 0..width {
            let u = (f64::from(x) + 0.5) / f64::from(width);
            let v = (f64::from(y) + 0.5) / f64::from(height);
            let uv = panorama_uv(turn * profile.lens.ray(u, v));
            out.set(x, y, sample(panorama, uv.x, uv.y));
        }
    }
    out
}

/// Bilinear sample of the panorama at uv, wrapping around in longitude.
fn sample(p: &RgbaImage, u: f64, v: f64) -> [u8; 4] {
    let (w, h) = (p.width as i64, p.height as i64);
    let fx = u * w as f64 - 0.5;
    let fy = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (fx.floor(), fy.floor());
    let (ax, ay) = (fx - x0, fy - y0);
    let at = |x: i64, y: i64| p.get(x.rem_euclid(w) as u32, y.clamp(0, h - 1) as u32);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (a, b, c, d) = (
        at(x0, y0),
        at(x0 + 1, y0),
        at(x0, y0 + 1),
        at(x0 + 1, y0 + 1),
    );
    let mut px = [0u8; 4];
    for i in 0..4 {
        let top = f64::from(a[i]) * (1.0 - ax) + f64::from(b[i]) * ax;
        let bottom = f64::from(c[i]) * (1.0 - ax) + f64::from(d[i]) * ax;
        px[i] = (top * (1.0 - ay) + bottom * ay).round() as u8;
    }
    px[3] = 255;
    px
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::registration::Lens;
    use crate::camera::rig::HeadPoses;
    use glam::{DQuat, DVec3};

    /// A panorama whose red channel is the longitude (0..255 over 360 degrees) and green the
    /// latitude.
    fn ramp() -> RgbaImage {
        let mut p = RgbaImage::new(720, 360, [0; 4]);
        for y in 0..360 {
            for x in 0..720 {
                p.set(x, y, [(x * 255 / 719) as u8, (y * 255 / 359) as u8, 0, 255]);
            }
        }
        p
    }

    fn profile() -> CameraProfile {
        CameraProfile {
            lens: Lens::Fov {
                horizontal: 60f64.to_radians(),
                vertical: 45f64.to_radians(),
            },
            pose: Pose::IDENTITY,
            scene_distance: 2.0,
        }
    }

    #[test]
    fn a_turned_head_sees_the_panorama_turned() {
        let p = ramp();
        let ahead = render(&p, &profile(), &Pose::IDENTITY, (64, 48));
        // Looking ahead the image centre shows longitude 0 (u = 0.5), the horizon.
        let c = ahead.get(32, 24);
        assert!((i32::from(c[0]) - 127).abs() <= 2 && (i32::from(c[1]) - 127).abs() <= 2);
        // Turned 45 degrees right (yaw -45 about +y): longitude +45 (u = 0.625).
        let right = Pose {
            position: DVec3::new(5.0, 1.0, 0.0),
            orientation: DQuat::from_rotation_y(-45f64.to_radians()),
        };
        let c = render(&p, &profile(), &right, (64, 48)).get(32, 24);
        assert!((f64::from(c[0]) - 0.625 * 255.0).abs() <= 2.0, "{c:?}");
    }

    /// A thread behind by three captures renders only the newest; one whose pose may still
    /// come holds back the later ones; one past the pose wait is dropped and said.
    #[test]
    fn only_the_newest_due_capture_is_rendered() {
        let poses = HeadPoses::default();
        let turned = Pose {
            position: DVec3::ZERO,
            orientation: DQuat::from_rotation_y(0.1),
        };
        let mut pending: VecDeque<i64> = [10, 20, 30, 40].into();
        for t in [10, 20] {
            poses.record(t, Some(Pose::IDENTITY));
        }
        poses.record(30, Some(turned));
        poses.record(40, Some(Pose::IDENTITY));
        // At 135 with latency 100 the captures at 10, 20 and 30 are due, 40 is not.
        let (newest, unlocated) = newest_due(&mut pending, 135, 100, &poses);
        assert_eq!(newest, Some((30, turned)));
        assert!(!unlocated);
        assert_eq!(pending, [40]);
        // A due capture with no answer yet waits (and the ones after it with it)...
        let mut pending: VecDeque<i64> = [50, 60].into();
        poses.record(60, Some(turned));
        assert_eq!(newest_due(&mut pending, 200, 100, &poses), (None, false));
        assert_eq!(pending, [50, 60]);
        // ...until the pose wait has passed: then it is dropped, and the later one delivered.
        let late = 50 + 100 + POSE_WAIT_NS;
        assert_eq!(
            newest_due(&mut pending, late, 100, &poses),
            (Some((60, turned)), true)
        );
        assert!(pending.is_empty());
    }

    #[test]
    fn poses_are_answered_by_time() {
        let poses = HeadPoses::default();
        poses.want(5);
        poses.want(9);
        assert_eq!(poses.wanted(), vec![5, 9]);
        assert!(poses.wanted().is_empty());
        assert_eq!(poses.take(5), None);
        poses.record(9, None);
        poses.record(5, Some(Pose::IDENTITY));
        assert_eq!(poses.take(5), Some(Some(Pose::IDENTITY)));
        assert_eq!(poses.take(9), Some(None));
        assert_eq!(poses.take(9), None);
    }
}
