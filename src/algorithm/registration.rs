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
    /// The lens that `[fx, fy, cx, cy, width, height]` (pixels, in the order and conventions of
    /// OpenCV's calibration: the config's `camera_intrinsics`) describe; None for all six 0,
    /// which says that none is given.
    pub fn from_intrinsics(k: [f32; 6]) -> Option<Lens> {
        if k == [0.0; 6] {
            return None;
        }
        let [fx, fy, cx, cy, width, height] = k.map(f64::from);
        Some(Lens::Pixels {
            fx,
            fy,
            cx,
            cy,
            width,
            height,
        })
    }

    /// Whether the lens can describe a camera: both angles in (0, 180) degrees, or finite
    /// intrinsics with positive focal lengths and image size.
    pub fn check(&self) -> Result<(), RegistrationError> {
        let usable = match *self {
            Lens::Fov {
                horizontal,
                vertical,
            } => {
                let ok = |a: f64| a.is_finite() && a > 0.0 && a < std::f64::consts::PI;
                ok(horizontal) && ok(vertical)
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
                all.iter().all(|x| x.is_finite())
                    && fx > 0.0
                    && fy > 0.0
                    && width > 0.0
                    && height > 0.0
            }
        };
        usable.then_some(()).ok_or(RegistrationError::BadProfile)
    }

    /// The camera-space ray (z = -1) through camera uv: the inverse of [`Lens::projection`],
    /// beside it so the two read the same conventions (the half texel, y up).
    pub fn ray(&self, u: f64, v: f64) -> DVec3 {
        match *self {
            Lens::Fov {
                horizontal,
                vertical,
            } => DVec3::new(
                (u - 0.5) * 2.0 * (horizontal / 2.0).tan(),
                -(v - 0.5) * 2.0 * (vertical / 2.0).tan(),
                -1.0,
            ),
            Lens::Pixels {
                fx,
                fy,
                cx,
                cy,
                width,
                height,
            } => DVec3::new(
                (u * width - cx - 0.5) / fx,
                -(v * height - cy - 0.5) / fy,
                -1.0,
            ),
        }
    }

    /// Takes a camera-space point to homogeneous camera uv (w = the depth in front, -z).
    fn projection(&self) -> Result<DMat3, RegistrationError> {
        // u = (fx x / -z + cx + 0.5) / width; v = (fy (-y) / -z + cy + 0.5) / height, with the
        // half pixel because texel centres are at (i + 0.5) / width in uv.
        self.check()?;
        let (ku, kv, pu, pv) = match *self {
            Lens::Fov {
                horizontal,
                vertical,
            } => {
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
            } => (
                fx / width,
                fy / height,
                (cx + 0.5) / width,
                (cy + 0.5) / height,
            ),
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
#[path = "registration_tests.rs"]
mod tests;
