//! Registration: where one view's display pixels lie in the camera image, from geometry. Given
//! the view's field of view and pose (what the runtime gives each projection view), the head
//! pose and a camera profile (its lens, its pose on the head, an assumed scene distance), it
//! computes the view's [`CameraMapping`]: the homography induced by a plane at the scene
//! distance, fronto-parallel to the view. It is exact for every point on that plane, and for
//! every point when the camera sits at the eye; it is affine when the camera's and the view's
//! axes are parallel.
//!
//! Conventions (OpenXR's): metres; view and camera spaces have +x right, +y up and look along
//! -z; field-of-view angles in radians with `angle_left` and `angle_down` negative for a view
//! centred on its axis. Image coordinates as in [`CameraMapping`]: origin top-left, v down.
//!
//! The head is OpenXR's VIEW reference space: the centroid of the views' origins (the point
//! between the eyes), oriented as the views on average. The camera's pose is given relative to
//! it, which is what a headset's drawings give ("the camera is 2 cm above and 6 cm in front of
//! the point between the eyes, tilted 10 degrees down"). Pure math: no OpenXR types, no GPU.

use super::mapping::CameraMapping;
use glam::{DMat3, DQuat, DVec2, DVec3};
use std::f64::consts::FRAC_PI_2;

/// A view's field of view, as OpenXR's XrFovf (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fov {
    pub angle_left: f64,
    pub angle_right: f64,
    pub angle_up: f64,
    pub angle_down: f64,
}

/// A rigid pose: where a space's origin is and how it is turned, in its parent space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub position: DVec3,
    pub orientation: DQuat,
}

/// The camera's lens as a pinhole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lens {
    /// Full horizontal and vertical field of view (radians), the principal point at the
    /// image's centre: what a spec sheet gives.
    Fov { horizontal: f64, vertical: f64 },
    /// Intrinsics in pixels for an image of `width` x `height`, as OpenCV's calibration gives
    /// them (origin top-left, y down, pixel centres at whole numbers).
    Pixels {
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        width: f64,
        height: f64,
    },
}

/// Everything about the camera that registration needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraProfile {
    pub lens: Lens,
    /// The camera's pose relative to the head (OpenXR VIEW space).
    pub pose: Pose,
    /// Distance (metres) of the plane, in front of each view, that is registered exactly.
    pub scene_distance: f64,
}

/// Why a view has no geometric mapping (the caller falls back to the manual one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RegistrationError {
    /// Angles not finite, not within (-90, 90) degrees, or left >= right / down >= up.
    BadFov,
    /// A position that is not finite or an orientation that is not a rotation.
    BadPose,
    /// A lens with a non-positive or non-finite size, or a non-positive scene distance.
    BadProfile,
    /// Part of the view's scene plane lies behind the camera.
    BehindCamera,
}

impl std::fmt::Display for RegistrationError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RegistrationError::BadFov => "the view's field of view is not usable",
            RegistrationError::BadPose => "a view's pose is not a valid pose",
            RegistrationError::BadProfile => "the camera profile is not usable",
            RegistrationError::BehindCamera => "the view's scene plane lies behind the camera",
        })
    }
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        position: DVec3::ZERO,
        orientation: DQuat::IDENTITY,
    };

    /// A pose from the numbers a user writes: position (metres) and pitch, yaw, roll (degrees,
    /// right-handed about the head's x, y and z axes, applied roll first, then pitch, then
    /// yaw: pitch > 0 tilts the camera up, yaw > 0 turns it left).
    pub fn from_position_pitch_yaw_roll(position: [f64; 3], degrees: [f64; 3]) -> Pose {
        let [pitch, yaw, roll] = degrees.map(f64::to_radians);
        Pose {
            position: DVec3::from(position),
            orientation: DQuat::from_rotation_y(yaw)
                * DQuat::from_rotation_x(pitch)
                * DQuat::from_rotation_z(roll),
        }
    }

    /// The pose with a unit orientation, or why not.
    fn checked(&self) -> Result<Pose, RegistrationError> {
        let length = self.orientation.length();
        if !self.position.is_finite() || !length.is_finite() || (length - 1.0).abs() > 1e-3 {
            return Err(RegistrationError::BadPose);
        }
        Ok(Pose {
            position: self.position,
            orientation: self.orientation / length,
        })
    }

    /// `child` (given in this pose's space) in this pose's parent space.
    pub fn then(&self, child: &Pose) -> Pose {
        Pose {
            position: self.position + self.orientation * child.position,
            orientation: self.orientation * child.orientation,
        }
    }

    pub fn inverse(&self) -> Pose {
        let q = self.orientation.inverse();
        Pose {
            position: -(q * self.position),
            orientation: q,
        }
    }
}

impl Fov {
    /// The tangents (left, right, up, down), or why the angles are not a field of view.
    fn tangents(&self) -> Result<[f64; 4], RegistrationError> {
        let angles = [
            self.angle_left,
            self.angle_right,
            self.angle_up,
            self.angle_down,
        ];
        let inside = angles.iter().all(|a| a.is_finite() && a.abs() < FRAC_PI_2);
        if !inside || self.angle_left >= self.angle_right || self.angle_down >= self.angle_up {
            return Err(RegistrationError::BadFov);
        }
        Ok(angles.map(f64::tan))
    }

    /// Takes homogeneous display uv to the view-space point on the plane z = -1 that the pixel
    /// shows (the third coordinate of the result is always -1).
    fn unprojection(&self) -> Result<DMat3, RegistrationError> {
        let [l, r, u, d] = self.tangents()?;
        // x = l + uv.x (r - l); y = u - uv.y (u - d); z = -1.
        Ok(DMat3::from_cols(
            DVec3::new(r - l, 0.0, 0.0),
            DVec3::new(0.0, d - u, 0.0),
            DVec3::new(l, u, -1.0),
        ))
    }
}

impl Lens {
    /// Takes a camera-space point to homogeneous camera uv (w = the depth in front, -z).
    fn projection(&self) -> Result<DMat3, RegistrationError> {
        // u = (fx x / -z + cx + 0.5) / width; v = (fy (-y) / -z + cy + 0.5) / height, with the
        // half pixel because texel centres are at (i + 0.5) / width in uv.
        let (ku, kv, pu, pv) = match *self {
            Lens::Fov {
                horizontal,
                vertical,
            } => {
                let ok = |a: f64| a.is_finite() && a > 0.0 && a < std::f64::consts::PI;
                if !ok(horizontal) || !ok(vertical) {
                    return Err(RegistrationError::BadProfile);
                }
                let (th, tv) = ((horizontal / 2.0).tan(), (vertical / 2.0).tan());
                (0.5 / th, 0.5 / tv, 0.5, 0.5)
            }
            Lens::Pixels {
                fx,
                fy,
                cx,
                cy,
                width,
                height,
            } => {
                let all = [fx, fy, cx, cy, width, height];
                if !all.iter().all(|x| x.is_finite()) || fx <= 0.0 || fy <= 0.0 {
                    return Err(RegistrationError::BadProfile);
                }
                if width <= 0.0 || height <= 0.0 {
                    return Err(RegistrationError::BadProfile);
                }
                (
                    fx / width,
                    fy / height,
                    (cx + 0.5) / width,
                    (cy + 0.5) / height,
                )
            }
        };
        // Rows: (ku, 0, -pu), (0, -kv, -pv), (0, 0, -1).
        Ok(DMat3::from_cols(
            DVec3::new(ku, 0.0, 0.0),
            DVec3::new(0.0, -kv, 0.0),
            DVec3::new(-pu, -pv, -1.0),
        ))
    }
}

/// The head (OpenXR VIEW space) from a frame's view poses: their centroid, turned as the
/// normalised sum of their orientations (signs aligned with the first). None without views or
/// with an invalid pose.
pub fn head_pose(views: &[Pose]) -> Option<Pose> {
    let checked: Vec<Pose> = views
        .iter()
        .map(|v| v.checked().ok())
        .collect::<Option<_>>()?;
    let first = checked.first()?.orientation;
    let mut sum = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    let mut centre = DVec3::ZERO;
    for v in &checked {
        let q = v.orientation;
        sum += if q.dot(first) < 0.0 { -q } else { q };
        centre += v.position;
    }
    let length = sum.length();
    (length > 1e-9).then(|| Pose {
        position: centre / checked.len() as f64,
        orientation: sum / length,
    })
}

/// Below this, a bottom-row entry of a mapping is rounding noise of parallel axes.
const AFFINE_EPSILON: f64 = 1e-12;

/// The mapping of the view with `fov` at `view` (both in the same reference space as `head`)
/// for a camera mounted on the head as `profile` says.
pub fn view_mapping(
    fov: &Fov,
    view: &Pose,
    head: &Pose,
    profile: &CameraProfile,
) -> Result<CameraMapping, RegistrationError> {
    let distance = profile.scene_distance;
    if !distance.is_finite() || distance <= 0.0 {
        return Err(RegistrationError::BadProfile);
    }
    let unproject = fov.unprojection()?;
    let project = profile.lens.projection()?;
    let camera = head.checked()?.then(&profile.pose.checked()?);
    // The view in camera space: p_camera = r p_view + t.
    let relative = camera.inverse().then(&view.checked()?);
    let r = DMat3::from_quat(relative.orientation);
    let t = relative.position;
    // The pixel at uv shows p_view = distance * unproject(uv), whose z is -distance, so
    // p_camera = distance r unproject(uv) + t = (distance r - t e_z^T) unproject(uv).
    let to_camera = r * distance - DMat3::from_cols(DVec3::ZERO, DVec3::ZERO, t);
    let h = project * to_camera * unproject;
    for corner in [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]] {
        let w = (h * DVec3::new(corner[0], corner[1], 1.0)).z;
        if !(w.is_finite() && w > distance * 1e-6) {
            return Err(RegistrationError::BehindCamera);
        }
    }
    Ok(normalised(h))
}

/// `h` scaled so its bottom-right entry is 1, with rounding noise in the bottom row dropped
/// (parallel axes then give an exactly affine mapping).
fn normalised(h: DMat3) -> CameraMapping {
    let mut m = CameraMapping::from_mat3(h * (1.0 / h.z_axis.z));
    for c in 0..2 {
        if m.rows[2][c].abs() < AFFINE_EPSILON {
            m.rows[2][c] = 0.0;
        }
    }
    m.rows[2][2] = 1.0;
    m
}

/// A per-eye correction on top of a mapping, in the view's own uv: the background picture is
/// scaled by `scale` about the view's centre, then moved by `offset` (fractions of the view's
/// width and height; +x right, +y down). What `contrastxr calibrate` nudges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nudge {
    pub offset: DVec2,
    pub scale: DVec2,
}

impl Nudge {
    pub const NONE: Nudge = Nudge {
        offset: DVec2::ZERO,
        scale: DVec2::ONE,
    };

    /// `mapping` with the correction: the display pixel at `c + scale (p - c) + offset` shows
    /// what the pixel at `p` showed before (c = the view's centre).
    pub fn apply(&self, mapping: &CameraMapping) -> CameraMapping {
        if *self == Nudge::NONE {
            return *mapping;
        }
        let c = DVec2::splat(0.5);
        let inverse_scale = DVec2::ONE / self.scale;
        let shift = c - (self.offset + c) * inverse_scale;
        let n = DMat3::from_cols(
            DVec3::new(inverse_scale.x, 0.0, 0.0),
            DVec3::new(0.0, inverse_scale.y, 0.0),
            DVec3::new(shift.x, shift.y, 1.0),
        );
        CameraMapping::from_mat3(mapping.to_mat3() * n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DISTANCE: f64 = 2.0;

    fn deg(a: f64) -> f64 {
        a.to_radians()
    }

    fn symmetric(h: f64, v: f64) -> Fov {
        Fov {
            angle_left: -deg(h) / 2.0,
            angle_right: deg(h) / 2.0,
            angle_up: deg(v) / 2.0,
            angle_down: -deg(v) / 2.0,
        }
    }

    /// A left eye's asymmetric field of view (more to the nose side... as real headsets give).
    const ASYMMETRIC: Fov = Fov {
        angle_left: -0.87,
        angle_right: 0.70,
        angle_up: 0.82,
        angle_down: -0.91,
    };

    /// Plain pinhole math, written out independently of the code under test: the display uv
    /// of a world point seen by a view (None behind it).
    fn display_uv(fov: &Fov, view: &Pose, p: DVec3) -> Option<DVec2> {
        let q = view.orientation.inverse() * (p - view.position);
        if q.z >= 0.0 {
            return None;
        }
        let (x, y) = (q.x / -q.z, q.y / -q.z);
        let (l, r) = (fov.angle_left.tan(), fov.angle_right.tan());
        let (u, d) = (fov.angle_up.tan(), fov.angle_down.tan());
        Some(DVec2::new((x - l) / (r - l), (u - y) / (u - d)))
    }

    /// The camera uv of a world point, as OpenCV would project it (pixel centres at whole
    /// numbers, so uv = (pixel + 0.5) / size).
    fn camera_uv(lens: &Lens, camera: &Pose, p: DVec3) -> DVec2 {
        let q = camera.orientation.inverse() * (p - camera.position);
        let (x, y) = (q.x / -q.z, -q.y / -q.z);
        match *lens {
            Lens::Fov {
                horizontal,
                vertical,
            } => DVec2::new(
                0.5 + x / (2.0 * (horizontal / 2.0).tan()),
                0.5 + y / (2.0 * (vertical / 2.0).tan()),
            ),
            Lens::Pixels {
                fx,
                fy,
                cx,
                cy,
                width,
                height,
            } => DVec2::new((fx * x + cx + 0.5) / width, (fy * y + cy + 0.5) / height),
        }
    }

    /// Points on the view's scene plane (z = -DISTANCE in the view) spread over the view.
    fn plane_points(fov: &Fov, view: &Pose) -> Vec<DVec3> {
        let mut out = Vec::new();
        for (a, b) in [
            (0.1, 0.2),
            (0.5, 0.5),
            (0.9, 0.15),
            (0.3, 0.8),
            (0.95, 0.95),
        ] {
            let x = fov.angle_left.tan() * (1.0 - a) + fov.angle_right.tan() * a;
            let y = fov.angle_up.tan() * (1.0 - b) + fov.angle_down.tan() * b;
            let local = DVec3::new(x, y, -1.0) * DISTANCE;
            out.push(view.position + view.orientation * local);
        }
        out
    }

    /// Two eyes 64 mm apart, the head turned and moved somewhere in the reference space.
    fn eyes(turned: DQuat) -> [Pose; 2] {
        let head = Pose {
            position: DVec3::new(0.3, 1.6, -0.4),
            orientation: turned,
        };
        [-0.032, 0.032].map(|x| {
            head.then(&Pose {
                position: DVec3::new(x, 0.0, 0.0),
                orientation: DQuat::IDENTITY,
            })
        })
    }

    #[track_caller]
    fn assert_registers(fov: &Fov, views: &[Pose], profile: &CameraProfile) -> Vec<CameraMapping> {
        let head = head_pose(views).unwrap();
        let camera = head.then(&profile.pose);
        let mut mappings = Vec::new();
        for view in views {
            let m = view_mapping(fov, view, &head, profile).unwrap();
            for p in plane_points(fov, view) {
                let shown_at = display_uv(fov, view, p).unwrap();
                let want = camera_uv(&profile.lens, &camera, p);
                let got = m.apply(shown_at);
                assert!(
                    (got - want).length() < 1e-9,
                    "point {p}: display {shown_at} -> {got}, camera sees it at {want}"
                );
            }
            mappings.push(m);
        }
        mappings
    }

    #[test]
    fn camera_at_the_eye_with_the_same_fov_is_identity() {
        let fov = symmetric(90.0, 70.0);
        let profile = CameraProfile {
            lens: Lens::Fov {
                horizontal: deg(90.0),
                vertical: deg(70.0),
            },
            pose: Pose::IDENTITY,
            scene_distance: DISTANCE,
        };
        let view = Pose {
            position: DVec3::new(1.0, 2.0, 3.0),
            orientation: DQuat::from_rotation_y(0.4),
        };
        let m = view_mapping(&fov, &view, &view, &profile).unwrap();
        for (got, want) in m
            .rows
            .iter()
            .flatten()
            .zip(CameraMapping::IDENTITY.rows.iter().flatten())
        {
            assert!((got - want).abs() < 1e-12, "{m:?}");
        }
        assert!(m.is_affine());
    }

    #[test]
    fn offset_camera_with_parallel_axes_registers_both_eyes_affinely() {
        let profile = CameraProfile {
            lens: Lens::Fov {
                horizontal: deg(100.0),
                vertical: deg(80.0),
            },
            pose: Pose::from_position_pitch_yaw_roll([0.01, 0.025, -0.07], [0.0; 3]),
            scene_distance: DISTANCE,
        };
        let views = eyes(DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.2, 0.1));
        for fov in [symmetric(90.0, 70.0), ASYMMETRIC] {
            let m = assert_registers(&fov, &views, &profile);
            assert!(m.iter().all(CameraMapping::is_affine), "{m:?}");
            // The eyes sit either side of the camera: their mappings differ in x only.
            assert!((m[0].rows[0][2] - m[1].rows[0][2]).abs() > 1e-3);
            assert!((m[0].rows[1][2] - m[1].rows[1][2]).abs() < 1e-9);
        }
    }

    #[test]
    fn rotated_camera_with_pixel_intrinsics_registers_through_a_homography() {
        let profile = CameraProfile {
            lens: Lens::Pixels {
                fx: 520.0,
                fy: 515.0,
                cx: 331.5,
                cy: 236.0,
                width: 640.0,
                height: 480.0,
            },
            pose: Pose::from_position_pitch_yaw_roll([-0.02, 0.03, -0.06], [-12.0, 4.0, 2.5]),
            scene_distance: DISTANCE,
        };
        let views = eyes(DQuat::from_rotation_y(-0.3));
        for fov in [symmetric(90.0, 90.0), ASYMMETRIC] {
            let m = assert_registers(&fov, &views, &profile);
            assert!(m.iter().all(|m| !m.is_affine()), "{m:?}");
        }
    }

    #[test]
    fn canted_views_share_the_head_between_them() {
        // Views turned 5 degrees outwards each: the head looks straight ahead between them.
        let mut views = eyes(DQuat::IDENTITY);
        views[0].orientation = DQuat::from_rotation_y(deg(5.0));
        views[1].orientation = DQuat::from_rotation_y(deg(-5.0));
        let head = head_pose(&views).unwrap();
        assert!(head.orientation.angle_between(DQuat::IDENTITY) < 1e-12);
        assert!((head.position - DVec3::new(0.3, 1.6, -0.4)).length() < 1e-12);
        let profile = CameraProfile {
            lens: Lens::Fov {
                horizontal: deg(110.0),
                vertical: deg(90.0),
            },
            pose: Pose::from_position_pitch_yaw_roll([0.0, 0.02, -0.05], [-5.0, 0.0, 0.0]),
            scene_distance: DISTANCE,
        };
        assert_registers(&ASYMMETRIC, &views, &profile);
    }

    #[test]
    fn a_camera_at_the_eye_registers_every_depth() {
        // Pure rotation: the homography holds off the plane too.
        let fov = ASYMMETRIC;
        let view = Pose::IDENTITY;
        let profile = CameraProfile {
            lens: Lens::Fov {
                horizontal: deg(120.0),
                vertical: deg(100.0),
            },
            pose: Pose::from_position_pitch_yaw_roll([0.0; 3], [3.0, -7.0, 1.0]),
            scene_distance: DISTANCE,
        };
        let m = view_mapping(&fov, &view, &view, &profile).unwrap();
        let camera = profile.pose;
        for p in [DVec3::new(0.3, -0.2, -0.5), DVec3::new(-4.0, 3.0, -25.0)] {
            let want = camera_uv(&profile.lens, &camera, p);
            let got = m.apply(display_uv(&fov, &view, p).unwrap());
            assert!((got - want).length() < 1e-9, "{got} vs {want}");
        }
    }

    #[test]
    fn unusable_inputs_are_refused() {
        let profile = CameraProfile {
            lens: Lens::Fov {
                horizontal: deg(90.0),
                vertical: deg(70.0),
            },
            pose: Pose::IDENTITY,
            scene_distance: DISTANCE,
        };
        let v = Pose::IDENTITY;
        let mut fov = symmetric(90.0, 70.0);
        fov.angle_left = 0.9;
        assert_eq!(
            view_mapping(&fov, &v, &v, &profile),
            Err(RegistrationError::BadFov)
        );
        let fov = symmetric(90.0, 70.0);
        let zero = Pose {
            orientation: DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            ..v
        };
        assert_eq!(
            view_mapping(&fov, &zero, &v, &profile),
            Err(RegistrationError::BadPose)
        );
        // A camera looking backwards sees none of the view's plane.
        let back = CameraProfile {
            pose: Pose::from_position_pitch_yaw_roll([0.0; 3], [0.0, 180.0, 0.0]),
            ..profile
        };
        assert_eq!(
            view_mapping(&fov, &v, &v, &back),
            Err(RegistrationError::BehindCamera)
        );
        let flat = CameraProfile {
            scene_distance: 0.0,
            ..profile
        };
        assert_eq!(
            view_mapping(&fov, &v, &v, &flat),
            Err(RegistrationError::BadProfile)
        );
        assert!(head_pose(&[]).is_none());
    }

    #[test]
    fn a_nudge_moves_and_scales_the_picture_about_the_centre() {
        let base = CameraMapping::affine([0.65, 0.6], [0.13, 0.17]);
        let nudge = Nudge {
            offset: DVec2::new(0.02, -0.01),
            scale: DVec2::new(1.1, 0.9),
        };
        let m = nudge.apply(&base);
        // What the pixel at p showed now shows at c + scale (p - c) + offset.
        for p in [
            DVec2::new(0.2, 0.3),
            DVec2::new(0.5, 0.5),
            DVec2::new(0.9, 0.1),
        ] {
            let moved = DVec2::splat(0.5) + nudge.scale * (p - DVec2::splat(0.5)) + nudge.offset;
            assert!((m.apply(moved) - base.apply(p)).length() < 1e-12);
        }
        assert_eq!(Nudge::NONE.apply(&base), base);
    }
}
