//! Tests of registration.rs: synthetic views, poses and camera profiles with known answers.

use super::*;

const DISTANCE: f64 = 2.0;

fn deg(a: f64) -> f64 {
    a.to_radians()
}

/// A camera of `horizontal` x `vertical` degrees at `pose`, registered at DISTANCE.
fn fov_camera(horizontal: f64, vertical: f64, pose: Pose) -> CameraProfile {
    CameraProfile {
        lens: Lens::Fov {
            horizontal: deg(horizontal),
            vertical: deg(vertical),
        },
        pose,
        scene_distance: DISTANCE,
    }
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
    let profile = fov_camera(90.0, 70.0, Pose::IDENTITY);
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
    let profile = fov_camera(
        100.0,
        80.0,
        Pose::from_position_pitch_yaw_roll([0.01, 0.025, -0.07], [0.0; 3]),
    );
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
    let profile = fov_camera(
        110.0,
        90.0,
        Pose::from_position_pitch_yaw_roll([0.0, 0.02, -0.05], [-5.0, 0.0, 0.0]),
    );
    assert_registers(&ASYMMETRIC, &views, &profile);
}

#[test]
fn a_camera_at_the_eye_registers_every_depth() {
    // Pure rotation: the homography holds off the plane too.
    let fov = ASYMMETRIC;
    let view = Pose::IDENTITY;
    let profile = fov_camera(
        120.0,
        100.0,
        Pose::from_position_pitch_yaw_roll([0.0; 3], [3.0, -7.0, 1.0]),
    );
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
    let profile = fov_camera(90.0, 70.0, Pose::IDENTITY);
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

#[test]
fn a_lens_ray_projects_back_to_its_uv() {
    let lenses = [
        Lens::Fov {
            horizontal: deg(100.0),
            vertical: deg(80.0),
        },
        Lens::Pixels {
            fx: 500.0,
            fy: 480.0,
            cx: 310.0,
            cy: 250.0,
            width: 640.0,
            height: 480.0,
        },
    ];
    for lens in lenses {
        let projection = lens.projection().unwrap();
        for (u, v) in [(0.5, 0.5), (0.1, 0.8), (0.93, 0.07)] {
            let p = projection * lens.ray(u, v);
            let (pu, pv) = (p.x / p.z, p.y / p.z);
            assert!(
                (pu - u).abs() < 1e-12 && (pv - v).abs() < 1e-12,
                "{lens:?}: ({u}, {v}) -> ({pu}, {pv})"
            );
        }
    }
}
