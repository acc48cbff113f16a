//! Reprojection across head motion: a camera frame was captured with the head at one pose and
//! is shown to an eye at another (the view's pose at display time). Both poses are taken in one
//! world-fixed space (OpenXR's LOCAL), so the mapping from the eye at display to the camera at
//! capture is the plane-induced homography of [`view_mapping`] with the head at capture:
//! rotation is compensated exactly (for every depth), translation exactly for the plane at the
//! profile's scene distance in front of the eye at display. Points nearer or farther than that
//! plane keep a parallax of (head translation) x (1/depth - 1/scene_distance) radians.
//!
//! Also the equirectangular panorama's angles, shared by the simulated `world:` camera: a
//! direction in the world space to the panorama's uv and back. Pure math: no OpenXR types.

use super::mapping::CameraMapping;
use super::registration::{head_pose, view_mapping, CameraProfile, Fov, Pose, RegistrationError};
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// Where the head was when the camera frame was captured, in the world space (LOCAL).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Capture {
    /// The head's pose at capture was located.
    Located(Pose),
    /// Not known (tracking lost, time out of range, compensation off): head-fixed mapping.
    HeadFixed,
}

/// A view's pose in the world space from its pose in the projection layer's space and that
/// space's pose in the world space at display time (an app's layer space may itself move).
pub fn view_in_world(layer_space: &Pose, view: &Pose) -> Pose {
    layer_space.then(view)
}

/// The mappings of one projection layer's views (`views` in the world space at display time)
/// from the camera at capture: with [`Capture::HeadFixed`], the head at display (the views'
/// centroid), which is the mapping without motion compensation.
pub fn views_mappings(
    fovs: &[Fov],
    views: &[Pose],
    capture: Capture,
    profile: &CameraProfile,
) -> Vec<Result<CameraMapping, RegistrationError>> {
    let head = match capture {
        Capture::Located(head) => Some(head),
        Capture::HeadFixed => head_pose(views),
    };
    fovs.iter()
        .zip(views)
        .map(|(fov, view)| match head {
            Some(head) => view_mapping(fov, view, &head, profile),
            None => Err(RegistrationError::BadPose),
        })
        .collect()
}

/// The equirectangular panorama uv of a world direction: longitude 0 is -z (OpenXR's forward)
/// at u = 0.5, growing towards +x (to the right); latitude +90 degrees (+y, up) at v = 0.
pub fn panorama_uv(direction: DVec3) -> DVec2 {
    let d = direction.normalize();
    let longitude = d.x.atan2(-d.z);
    let latitude = d.y.clamp(-1.0, 1.0).asin();
    DVec2::new(0.5 + longitude / TAU, 0.5 - latitude / PI)
}

/// The world direction (unit) that panorama uv shows: the inverse of [`panorama_uv`].
pub fn panorama_direction(uv: DVec2) -> DVec3 {
    let longitude = (uv.x - 0.5) * TAU;
    let latitude = (0.5 - uv.y) * PI;
    DVec3::new(
        latitude.cos() * longitude.sin(),
        latitude.sin(),
        -latitude.cos() * longitude.cos(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::registration::Lens;
    use glam::DQuat;

    const DISTANCE: f64 = 2.0;

    /// The display uv at which a view shows a world point: pinhole math written out here.
    fn display_uv(fov: &Fov, view: &Pose, p: DVec3) -> DVec2 {
        let q = view.orientation.inverse() * (p - view.position);
        let (x, y) = (q.x / -q.z, q.y / -q.z);
        let (l, r) = (fov.angle_left.tan(), fov.angle_right.tan());
        let (u, d) = (fov.angle_up.tan(), fov.angle_down.tan());
        DVec2::new((x - l) / (r - l), (u - y) / (u - d))
    }

    /// The camera uv of a world point for a lens given by its full angles.
    fn camera_uv(h: f64, v: f64, camera: &Pose, p: DVec3) -> DVec2 {
        let q = camera.orientation.inverse() * (p - camera.position);
        let (x, y) = (q.x / -q.z, -q.y / -q.z);
        DVec2::new(
            0.5 + x / (2.0 * (h / 2.0).tan()),
            0.5 + y / (2.0 * (v / 2.0).tan()),
        )
    }

    fn fov() -> Fov {
        Fov {
            angle_left: -0.8,
            angle_right: 0.7,
            angle_up: 0.75,
            angle_down: -0.85,
        }
    }

    fn profile() -> CameraProfile {
        CameraProfile {
            lens: Lens::Fov {
                horizontal: 100f64.to_radians(),
                vertical: 80f64.to_radians(),
            },
            // 2 cm right, 3 cm up, 7 cm in front of the eyes' centre, tilted down 8 degrees.
            pose: Pose::from_position_pitch_yaw_roll([0.02, 0.03, -0.07], [-8.0, 2.0, 1.0]),
            scene_distance: DISTANCE,
        }
    }

    fn head(yaw_deg: f64, pitch_deg: f64, position: [f64; 3]) -> Pose {
        Pose {
            position: DVec3::from(position),
            orientation: DQuat::from_rotation_y(yaw_deg.to_radians())
                * DQuat::from_rotation_x(pitch_deg.to_radians()),
        }
    }

    fn eyes(head: &Pose) -> [Pose; 2] {
        [-0.032, 0.032].map(|x| {
            head.then(&Pose {
                position: DVec3::new(x, 0.0, 0.0),
                orientation: DQuat::IDENTITY,
            })
        })
    }

    /// A world point on the eye's scene plane, seen at tangents (x, y) of the view.
    fn on_plane(view: &Pose, x: f64, y: f64, depth: f64) -> DVec3 {
        view.position + view.orientation * (DVec3::new(x, y, -1.0) * depth)
    }

    const SPOTS: [(f64, f64); 5] = [
        (0.0, 0.0),
        (-0.6, 0.5),
        (0.5, -0.6),
        (0.3, 0.4),
        (-0.4, -0.3),
    ];

    /// Largest camera-uv error of the mapping over points at `depth` in front of the view.
    fn worst_error(m: &CameraMapping, view: &Pose, camera: &Pose, depth: f64) -> f64 {
        let Lens::Fov {
            horizontal,
            vertical,
        } = profile().lens
        else {
            unreachable!()
        };
        SPOTS
            .iter()
            .map(|&(x, y)| {
                let p = on_plane(view, x, y, depth);
                let want = camera_uv(horizontal, vertical, camera, p);
                (m.apply(display_uv(&fov(), view, p)) - want).length()
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_head_at_capture_registers_the_plane_after_a_turn_and_a_step() {
        // Captured with the head turned 4 degrees right and 5 cm to the left of where it is
        // at display, with an offset and tilted camera.
        let at_capture = head(-4.0, 1.5, [0.25, 1.6, -0.3]);
        let at_display = head(3.0, -1.0, [0.30, 1.61, -0.32]);
        let views = eyes(&at_display);
        let camera = at_capture.then(&profile().pose);
        let m = views_mappings(
            &[fov(); 2],
            &views,
            Capture::Located(at_capture),
            &profile(),
        );
        for (view, m) in views.iter().zip(&m) {
            let m = m.as_ref().unwrap();
            assert!(worst_error(m, view, &camera, DISTANCE) < 1e-9);
            // Off the plane only translation is left: parallax, not the whole motion.
            let off = worst_error(m, view, &camera, 5.0);
            assert!(off > 1e-4 && off < 0.02, "{off}");
        }
    }

    #[test]
    fn a_pure_turn_is_compensated_at_every_depth() {
        let position = [0.0, 1.6, 0.0];
        let at_capture = head(10.0, -3.0, position);
        let at_display = head(0.0, 0.0, position);
        let mut p = profile();
        p.pose.position = DVec3::ZERO;
        let views = [at_display];
        let camera = at_capture.then(&p.pose);
        let m = views_mappings(&[fov()], &views, Capture::Located(at_capture), &p);
        let m = m[0].as_ref().unwrap();
        for depth in [0.5, DISTANCE, 40.0] {
            assert!(worst_error(m, &views[0], &camera, depth) < 1e-9);
        }
    }

    #[test]
    fn head_fixed_misses_by_the_turn_and_matches_without_motion() {
        let at_capture = head(5.0, 0.0, [0.0, 1.6, 0.0]);
        let at_display = head(0.0, 0.0, [0.0, 1.6, 0.0]);
        let views = eyes(&at_display);
        let camera = at_capture.then(&profile().pose);
        let fixed = views_mappings(&[fov(); 2], &views, Capture::HeadFixed, &profile());
        let fixed = fixed[0].as_ref().unwrap();
        // 5 degrees over a 100 degree camera image: about 0.04 of its width.
        let err = worst_error(fixed, &views[0], &camera, DISTANCE);
        assert!(err > 0.03, "{err}");
        // Without motion the head-fixed mapping is the compensated one.
        let still = views_mappings(
            &[fov(); 2],
            &views,
            Capture::Located(head_pose(&views).unwrap()),
            &profile(),
        );
        let camera = at_display.then(&profile().pose);
        let still = still[0].as_ref().unwrap();
        assert!(worst_error(still, &views[0], &camera, DISTANCE) < 1e-9);
    }

    #[test]
    fn a_moving_layer_space_carries_the_views_into_the_world() {
        let space = head(30.0, 0.0, [1.0, 0.0, -2.0]);
        let view = head(-10.0, 5.0, [0.1, 1.5, 0.2]);
        let world = view_in_world(&space, &view);
        let p = DVec3::new(0.3, -0.2, -1.0);
        // A point given in the view lands in the same world place either way.
        let direct = space.position + space.orientation * (view.position + view.orientation * p);
        assert!((world.position + world.orientation * p - direct).length() < 1e-12);
    }

    #[test]
    fn panorama_angles_round_trip_and_face_forward() {
        assert!((panorama_uv(DVec3::NEG_Z) - DVec2::new(0.5, 0.5)).length() < 1e-12);
        assert!((panorama_uv(DVec3::X) - DVec2::new(0.75, 0.5)).length() < 1e-12);
        assert!((panorama_uv(DVec3::Y).y).abs() < 1e-12);
        for uv in [
            DVec2::new(0.1, 0.3),
            DVec2::new(0.8, 0.7),
            DVec2::new(0.5, 0.5),
        ] {
            assert!((panorama_uv(panorama_direction(uv)) - uv).length() < 1e-12);
        }
    }
}
