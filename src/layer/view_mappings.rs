//! Each view's camera mapping at xrEndFrame: from the projection view's XrFovf and pose and the
//! config's camera profile ([`crate::algorithm::registration`]), unless the manual
//! `fov_scale`/`fov_offset` were set to other than their defaults (an explicit override) or no profile is given (the
//! default manual mapping); then the eye's correction (`left_eye_*`, `right_eye_*`). Cheap: a
//! few 3x3 products per view and frame. Where each view's mapping comes from is logged once
//! per settings generation.

use super::live_settings::Settings;
use super::log;
use crate::algorithm::mapping::CameraMapping;
use crate::algorithm::registration::{head_pose, view_mapping, Fov, Nudge, Pose};
use crate::config::EYES;
use glam::{DQuat, DVec3};
use openxr_sys as xr;
use std::collections::HashSet;
use std::mem::{discriminant, Discriminant};
use std::sync::{Mutex, OnceLock};

/// Where a view's mapping came from (before the eye's correction).
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// `fov = false`: camera_uv = display_uv.
    Off,
    /// `fov_scale`/`fov_offset` set (to other than their defaults) in the config or environment.
    Manual,
    /// The camera profile and the view's field of view and pose.
    Profile,
    /// The camera profile could not register this view (the reason); the manual mapping.
    ProfileFailed(String),
    /// No camera profile: the default `fov_scale`/`fov_offset` (the paper's HoloLens values).
    Default,
}

impl Source {
    fn describe(&self) -> String {
        match self {
            Source::Off => "none (fov = false: camera_uv = display_uv)".into(),
            Source::Manual => "the manual fov_scale/fov_offset (set in the config)".into(),
            Source::Profile => "the camera profile and the view's field of view and pose".into(),
            Source::ProfileFailed(why) => {
                format!("the manual fov_scale/fov_offset: the camera profile cannot register it ({why})")
            }
            Source::Default => {
                "the default fov_scale/fov_offset (no camera profile in the config)".into()
            }
        }
    }
}

/// What a projection view says about where it looks from.
#[derive(Clone, Copy, Debug)]
pub struct ViewGeometry {
    pub fov: Fov,
    pub pose: Pose,
}

impl ViewGeometry {
    pub fn from_xr(view: &xr::CompositionLayerProjectionView) -> ViewGeometry {
        let (f, p) = (view.fov, view.pose);
        let q = p.orientation;
        ViewGeometry {
            fov: Fov {
                angle_left: f64::from(f.angle_left),
                angle_right: f64::from(f.angle_right),
                angle_up: f64::from(f.angle_up),
                angle_down: f64::from(f.angle_down),
            },
            pose: Pose {
                position: DVec3::new(
                    f64::from(p.position.x),
                    f64::from(p.position.y),
                    f64::from(p.position.z),
                ),
                orientation: DQuat::from_xyzw(
                    f64::from(q.x),
                    f64::from(q.y),
                    f64::from(q.z),
                    f64::from(q.w),
                ),
            },
        }
    }
}

/// The mapping without registration: identity with `fov = false`, else the manual one.
fn manual(settings: &Settings) -> (CameraMapping, Source) {
    let source = if !settings.params.fov {
        Source::Off
    } else if settings.manual_mapping_set() {
        Source::Manual
    } else {
        Source::Default
    };
    (settings.params.camera_mapping(), source)
}

/// The mappings of one projection layer's views (index = view index: 0 left eye, 1 right).
pub fn projection_mappings(
    settings: &Settings,
    views: &[ViewGeometry],
) -> Vec<(CameraMapping, Source)> {
    let profile = settings.registration.profile();
    let base = manual(settings);
    let poses: Vec<Pose> = views.iter().map(|v| v.pose).collect();
    let head = head_pose(&poses);
    views
        .iter()
        .enumerate()
        .map(|(eye, view)| {
            let (mapping, source) = match (&base.1, profile, head) {
                (Source::Default, Some(profile), Some(head)) => {
                    match view_mapping(&view.fov, &view.pose, &head, &profile) {
                        Ok(m) => (m, Source::Profile),
                        Err(e) => (base.0, Source::ProfileFailed(e.to_string())),
                    }
                }
                (Source::Default, Some(_), None) => (
                    base.0,
                    Source::ProfileFailed("a view's pose is not a valid pose".into()),
                ),
                _ => base.clone(),
            };
            (settings.registration.nudge(eye).apply(&mapping), source)
        })
        .collect()
}

/// The mapping of a quad layer: the manual one (a quad has no eye's field of view).
pub fn quad_mapping(settings: &Settings) -> CameraMapping {
    manual(settings).0
}

/// Whether (generation, view, kind of source) is new: checked every frame, so no allocation.
fn first_time(generation: u64, view: usize, source: &Source) -> bool {
    type Seen = HashSet<(u64, usize, Discriminant<Source>)>;
    static SEEN: OnceLock<Mutex<Seen>> = OnceLock::new();
    let seen = SEEN.get_or_init(Default::default);
    // Only set operations happen under this lock.
    let mut seen = seen.lock().unwrap_or_else(|p| p.into_inner());
    seen.insert((generation, view, discriminant(source)))
}

/// Logs, once per settings generation and view, where the view's mapping came from.
pub fn log_mapping(settings: &Settings, view: usize, mapping: &CameraMapping, source: &Source) {
    if !first_time(settings.generation, view, source) {
        return;
    }
    let r = &settings.registration;
    let (label, correction) = match EYES.get(view) {
        Some(eye) if r.nudge(view) != Nudge::NONE => (
            format!("view {view} ({eye} eye)"),
            format!(
                ", corrected by {eye}_eye_offset {:?} and {eye}_eye_scale {:?}",
                r.eye_offset[view], r.eye_scale[view]
            ),
        ),
        Some(eye) => (format!("view {view} ({eye} eye)"), String::new()),
        None => (format!("view {view}"), String::new()),
    };
    // Adding 0.0 turns -0.0 into 0.0.
    let rows = mapping
        .rows
        .map(|r| r.map(|x| (x * 1e5).round() / 1e5 + 0.0));
    log::info(&format!(
        "{label}: camera mapping from {}{correction}: camera_uv = {rows:?} (display_uv, 1)",
        source.describe()
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{resolve, Env, Source as File};
    use glam::DVec2;
    use std::path::Path;

    fn settings(text: &str) -> Settings {
        let file = File {
            path: Path::new("/c.toml"),
            text,
        };
        let r = resolve("", Some(file), &Env::default());
        assert!(r.problems.is_empty(), "{:?}", r.problems);
        r.settings
    }

    /// Two eyes 64 mm apart looking down -z with 90 x 90 degree views.
    fn eyes() -> Vec<ViewGeometry> {
        [-0.032, 0.032]
            .map(|x| ViewGeometry {
                fov: Fov {
                    angle_left: -std::f64::consts::FRAC_PI_4,
                    angle_right: std::f64::consts::FRAC_PI_4,
                    angle_up: std::f64::consts::FRAC_PI_4,
                    angle_down: -std::f64::consts::FRAC_PI_4,
                },
                pose: Pose {
                    position: DVec3::new(x, 1.7, 0.0),
                    orientation: DQuat::IDENTITY,
                },
            })
            .to_vec()
    }

    #[test]
    fn without_a_profile_both_eyes_get_the_default_manual_mapping() {
        let s = settings("");
        let m = projection_mappings(&s, &eyes());
        assert_eq!(m[0], (s.params.camera_mapping(), Source::Default));
        assert_eq!(m[1], m[0]);
    }

    #[test]
    fn a_profile_registers_each_eye() {
        // A camera with the views' field of view at the point between the eyes: each eye's
        // mapping is the identity shifted by half the eye distance seen at 2 m, in opposite
        // directions (32 mm at 2 m over a 4 m wide view: 0.008 of the width).
        let s = settings("camera_fov = [90, 90]\n");
        let m = projection_mappings(&s, &eyes());
        for (eye, sign) in [(0, -1.0), (1, 1.0)] {
            assert_eq!(m[eye].1, Source::Profile);
            let got = m[eye].0.apply(DVec2::new(0.5, 0.5));
            let want = DVec2::new(0.5 + sign * 0.008, 0.5);
            assert!((got - want).length() < 1e-12, "{eye}: {got}");
        }
    }

    #[test]
    fn a_set_manual_mapping_overrides_the_profile_and_corrections_apply_per_eye() {
        let s = settings(
            "camera_fov = [90, 90]\nfov_scale = [0.5, 0.5]\nfov_offset = [0.25, 0.25]\n\
             right_eye_offset = [0.1, 0]\n",
        );
        let m = projection_mappings(&s, &eyes());
        assert_eq!(m[0], (s.params.camera_mapping(), Source::Manual));
        assert_eq!(m[1].1, Source::Manual);
        // The right eye's picture moved right by 0.1: what the centre showed is now at 0.6.
        let got = m[1].0.apply(DVec2::new(0.6, 0.5));
        assert!((got - DVec2::new(0.5, 0.5)).length() < 1e-6, "{got}");
    }

    #[test]
    fn a_view_the_profile_cannot_register_falls_back() {
        let s = settings("camera_fov = [90, 90]\ncamera_rotation = [0, 180, 0]\n");
        let m = projection_mappings(&s, &eyes());
        assert!(matches!(m[0].1, Source::ProfileFailed(_)), "{:?}", m[0]);
        assert_eq!(m[0].0, s.params.camera_mapping());
        let off = settings("camera_fov = [90, 90]\nfov = false\n");
        assert_eq!(projection_mappings(&off, &eyes())[0].1, Source::Off);
    }
}
