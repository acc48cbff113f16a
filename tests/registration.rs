//! Per-eye registration in the layer, against the real Monado runtime in the sandbox (see
//! tests/common/mod.rs for the skip/require rule): the system's `[device."..."]` table applies
//! once the session names the system, each projection view gets its own mapping from the
//! camera profile (or the manual one when set, or the default without a profile), and
//! `contrastxr calibrate` reaches a running app: its nudges change the mapping of the eye it
//! calibrates, seen in the captured frames' `camera_mapping`. The geometry itself is tested
//! against plain pinhole math in src/algorithm/registration.rs.

mod common;

use common::{layer_lines, sandbox, scratch_dir, wait_for, CLI, XR_CLIENT};
use serde_json::Value;
use std::io::Write;
use std::path::Path;
use std::time::Duration;

const SYSTEM: &str = "Monado: Simulated HMD";

fn run_client(config: &Path, env: &[(&str, &str)], frames: &str) -> Option<Vec<String>> {
    let sandbox = sandbox()?;
    let config = config.to_string_lossy().into_owned();
    let mut all = vec![
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_CONFIG", config.as_str()),
    ];
    all.extend(env);
    let cmd = [XR_CLIENT, "--json", "--frames", frames, "--size", "64x48"];
    let run = sandbox.run(&cmd, &all);
    run.assert_success();
    Some(layer_lines(&run))
}

fn mapping_lines(lines: &[String], view: usize) -> Vec<&String> {
    let prefix = format!("view {view} (");
    lines.iter().filter(|l| l.starts_with(&prefix)).collect()
}

#[test]
fn each_eye_is_registered_from_the_device_profile() {
    let dir = scratch_dir("registration-device");
    let config = dir.join("config.toml");
    let profile = "camera_fov = [100, 80]\ncamera_position = [0, 0.02, -0.06]\n";
    // Line 1: a problem at the top level; line 6: one in the device table.
    std::fs::write(
        &config,
        format!("blur_size = 4\nlambda_e = 0.5\n[device.\"{SYSTEM}\"]\n{profile}scene_distance = -1\n[device.\"Other HMD\"]\nscene_distance = 9\n"),
    )
    .unwrap();
    let Some(lines) = run_client(&config, &[], "10") else {
        return;
    };
    let system = format!("system \"{SYSTEM}\"");
    assert!(lines.iter().any(|l| l.starts_with(&system)), "{lines:#?}");
    // The device table's values are logged with their origin (file, table and line).
    let origin = format!(
        "setting camera_fov = [100.0, 80.0]  # {} [device.\"{SYSTEM}\"]:4",
        config.display()
    );
    assert!(lines.contains(&origin), "{lines:#?}");
    // Each problem is named once: the top level's at start, the device table's when it applies.
    for (line, key) in [(1, "blur_size"), (6, "scene_distance")] {
        let named = format!("config {}:{line}: {key}: ", config.display());
        let n = lines.iter().filter(|l| l.starts_with(&named)).count();
        assert_eq!(n, 1, "{key}: {lines:#?}");
    }
    assert!(
        !lines.iter().any(|l| l.contains("scene_distance = 9")),
        "{lines:#?}"
    );
    let (left, right) = (mapping_lines(&lines, 0), mapping_lines(&lines, 1));
    assert_eq!((left.len(), right.len()), (1, 1), "{lines:#?}");
    for l in [left[0], right[0]] {
        assert!(l.contains("from the camera profile"), "{l}");
    }
    // The eyes sit either side of the camera: their mappings differ.
    let rows = |l: &str| l.split("camera_uv = ").nth(1).unwrap().to_string();
    assert_ne!(rows(left[0]), rows(right[0]));

    // The manual mapping, set, overrides the profile; without a profile it is the default.
    std::fs::write(&config, format!("{profile}fov_offset = [0.1, 0.2]\n")).unwrap();
    let Some(lines) = run_client(&config, &[], "10") else {
        return;
    };
    let left = mapping_lines(&lines, 0);
    assert!(
        left[0].contains("the manual fov_scale/fov_offset (set"),
        "{left:#?}"
    );
    std::fs::write(&config, "lambda_e = 0.5\n").unwrap();
    let Some(lines) = run_client(&config, &[], "10") else {
        return;
    };
    let left = mapping_lines(&lines, 0);
    assert!(
        left[0].contains("the default fov_scale/fov_offset"),
        "{left:#?}"
    );
}

/// Runs `contrastxr calibrate` on `config`, feeding it `steps` one by one, `pause` apart.
fn calibrate_slowly(config: &Path, steps: &[&str], pause: Duration) -> String {
    let mut child = std::process::Command::new(CLI)
        .arg("calibrate")
        .env("CONTRASTXR_CONFIG", config)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("run contrastxr calibrate");
    let mut input = child.stdin.take().expect("stdin");
    for step in steps {
        std::thread::sleep(pause);
        writeln!(input, "{step}").expect("write to calibrate");
    }
    std::thread::sleep(pause);
    drop(input);
    let out = child.wait_with_output().expect("calibrate ends");
    assert!(out.status.success());
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Each captured frame's view-0 and view-1 JSON, in frame order.
fn captured(dir: &Path) -> Vec<[Value; 2]> {
    let json = |f: u64, v: usize| -> Option<Value> {
        let text = std::fs::read_to_string(dir.join(format!("frame-{f}-view-{v}.json"))).ok()?;
        serde_json::from_str(&text).ok()
    };
    (0..)
        .map_while(|f| Some([json(f, 0)?, json(f, 1)?]))
        .collect()
}

fn offset_x(view: &Value) -> f64 {
    view["camera_mapping"][0][2]
        .as_f64()
        .expect("camera_mapping")
}

#[test]
fn calibrate_reaches_a_running_app() {
    if sandbox().is_none() {
        return;
    }
    let dir = scratch_dir("registration-calibrate");
    let config = dir.join("config.toml");
    std::fs::write(&config, "lambda_e = 0.5\n").unwrap();
    let capture = dir.join("capture");
    let capture_s = capture.to_string_lossy().into_owned();
    let env = [
        ("CONTRASTXR_CAPTURE_DIR", capture_s.as_str()),
        ("CONTRASTXR_CAPTURE_FRAMES", "100000"),
    ];
    let (lines, out) = std::thread::scope(|s| {
        let run = s.spawn(|| run_client(&config, &env, "240"));
        assert!(wait_for(
            &capture.join("frame-5-view-1.json"),
            Duration::from_secs(60)
        ));
        // Left eye: 4 steps (0.02 of the view) right; right eye untouched.
        let steps = ["right right", "right right", "next"];
        let out = calibrate_slowly(&config, &steps, Duration::from_millis(1500));
        (run.join().expect("client thread"), out)
    });
    let Some(lines) = lines else { return };
    assert!(out.contains("left_eye_offset = [0.02, 0]"), "{out}");
    // Mode background while calibrating, and back to the file's own (none: enhance) after.
    let reloads: Vec<&String> = lines.iter().filter(|l| l.contains("reloaded:")).collect();
    assert!(
        reloads
            .iter()
            .any(|l| l.contains("mode \"enhance\" -> \"background\"")),
        "{reloads:#?}"
    );
    assert!(
        reloads
            .iter()
            .any(|l| l.contains("mode \"background\" -> \"enhance\"")),
        "{reloads:#?}"
    );
    assert_eq!(
        std::fs::read_to_string(&config)
            .unwrap()
            .matches("mode")
            .count(),
        0
    );
    // The captures: the left eye's picture moved right by 0.02 of the view, so the left view's
    // mapping shifts by -0.02 times its x scale; the right view's stays.
    let frames = captured(&capture);
    let (first, last) = (&frames[0], frames.last().expect("captures"));
    let scale = first[0]["camera_mapping"][0][0].as_f64().unwrap();
    let moved = offset_x(&last[0]) - offset_x(&first[0]);
    assert!(
        (moved + 0.02 * scale).abs() < 1e-6,
        "{moved} vs {}",
        -0.02 * scale
    );
    assert_eq!(offset_x(&last[1]), offset_x(&first[1]));
    let corrected: Vec<&String> = mapping_lines(&lines, 0)
        .into_iter()
        .filter(|l| l.contains("corrected by left_eye_offset [0.02, 0.0]"))
        .collect();
    assert!(!corrected.is_empty(), "{lines:#?}");
}

/// A scene point drawn as a dot in a synthetic camera frame shows at the right display pixel of
/// each eye after the CPU reference maps the frame through that eye's registered mapping
/// (parallel axes: affine, so the manual form of the reference applies). Where the point is in
/// the camera and in each eye is plain pinhole math here. No sandbox needed.
#[test]
fn a_scene_point_lands_on_its_display_pixel_in_each_eye() {
    use contrastxr::algorithm::registration::{
        head_pose, view_mapping, CameraProfile, Fov, Lens, Pose,
    };
    use contrastxr::algorithm::Params;
    use contrastxr::image::RgbaImage;
    use glam::{DQuat, DVec3};

    let (hfov, vfov) = (100f64.to_radians(), 80f64.to_radians());
    let profile = CameraProfile {
        lens: Lens::Fov {
            horizontal: hfov,
            vertical: vfov,
        },
        pose: Pose::from_position_pitch_yaw_roll([0.0, 0.02, -0.06], [0.0; 3]),
        scene_distance: 2.0,
    };
    let fov = Fov {
        angle_left: -0.8,
        angle_right: 0.7,
        angle_up: 0.65,
        angle_down: -0.75,
    };
    let eyes = [-0.032, 0.032].map(|x| Pose {
        position: DVec3::new(x, 1.6, 0.0),
        orientation: DQuat::IDENTITY,
    });
    let head = head_pose(&eyes).unwrap();
    let camera_pose = head.then(&profile.pose);
    // A point 2 m in front of the eyes, up and to the right.
    let p = DVec3::new(0.5, 1.9, -2.0);
    let (cw, ch) = (320u32, 240u32);
    let q = p - camera_pose.position;
    let cx = (0.5 + (q.x / -q.z) / (2.0 * (hfov / 2.0).tan())) * f64::from(cw);
    let cy = (0.5 - (q.y / -q.z) / (2.0 * (vfov / 2.0).tan())) * f64::from(ch);
    let mut camera = RgbaImage::new(cw, ch, [0, 0, 0, 255]);
    for dy in -1..=1 {
        for dx in -1..=1 {
            camera.set(
                (cx as i64 + dx) as u32,
                (cy as i64 + dy) as u32,
                [255, 255, 255, 255],
            );
        }
    }
    let (dw, dh) = (200u32, 160u32);
    for eye in &eyes {
        let m = view_mapping(&fov, eye, &head, &profile).unwrap();
        assert!(
            m.is_affine() && m.rows[0][1] == 0.0 && m.rows[1][0] == 0.0,
            "{m:?}"
        );
        let params = Params {
            fov_scale: [m.rows[0][0] as f32, m.rows[1][1] as f32],
            fov_offset: [m.rows[0][2] as f32, m.rows[1][2] as f32],
            ..Params::default()
        };
        let shown = contrastxr::background_preparation::fov_sharp(&camera, dw, dh, &params);
        let brightest = (0..shown.len())
            .max_by(|&a, &b| shown[a].x.total_cmp(&shown[b].x))
            .unwrap();
        let got = (
            (brightest as u32 % dw) as f64,
            (brightest as u32 / dw) as f64,
        );
        let e = p - eye.position;
        let (x, y) = (e.x / -e.z, e.y / -e.z);
        let (l, r) = (fov.angle_left.tan(), fov.angle_right.tan());
        let (u, d) = (fov.angle_up.tan(), fov.angle_down.tan());
        let want = (
            (x - l) / (r - l) * f64::from(dw),
            (u - y) / (u - d) * f64::from(dh),
        );
        assert!(
            (got.0 + 0.5 - want.0).abs() <= 1.5 && (got.1 + 0.5 - want.1).abs() <= 1.5,
            "eye at {}: the dot shows at {got:?}, the eye sees the point at {want:?}",
            eye.position
        );
    }
}

/// End to end: in `mode = background` each eye shows the camera frame through its own
/// registered mapping: the captured output of each view equals the CPU reference's background
/// (blurred, mapped through the view's `camera_mapping`, times the transmittance) within 2 code
/// values, and the two eyes differ. The profile has parallel axes, so the mappings are affine
/// and the reference's manual form computes them.
#[test]
fn each_eye_shows_the_camera_through_its_own_mapping() {
    use contrastxr::algorithm::Params;
    use contrastxr::image::RgbaImage;
    let dir = scratch_dir("registration-background");
    let config = dir.join("config.toml");
    std::fs::write(
        &config,
        "mode = \"background\"\ncamera_fov = [100, 80]\ncamera_position = [0, 0.02, -0.06]\n",
    )
    .unwrap();
    let capture = dir.join("capture");
    let image = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/background-grey-office.png");
    let background = format!("image:{}", image.display());
    let capture_s = capture.to_string_lossy().into_owned();
    let env = [
        ("CONTRASTXR_BACKGROUND", background.as_str()),
        ("CONTRASTXR_CAPTURE_DIR", capture_s.as_str()),
    ];
    let Some(_) = run_client(&config, &env, "10") else {
        return;
    };
    let frames = captured(&capture);
    let views = frames.first().expect("a captured frame");
    let load = |v: usize, kind: &str| {
        RgbaImage::load_png(&capture.join(format!("frame-0-view-{v}-{kind}.png"))).unwrap()
    };
    let mut outputs = Vec::new();
    for (v, json) in views.iter().enumerate() {
        let m = &json["camera_mapping"];
        let at = |r: usize, c: usize| m[r][c].as_f64().unwrap();
        assert_eq!((at(2, 0), at(2, 1)), (0.0, 0.0), "affine");
        assert!(
            at(0, 1).abs() < 1e-9 && at(1, 0).abs() < 1e-9,
            "no shear: {m}"
        );
        let params = Params {
            fov_scale: [at(0, 0) as f32, at(1, 1) as f32],
            fov_offset: [at(0, 2) as f32, at(1, 2) as f32],
            ..Params::default()
        };
        let output = load(v, "output");
        let camera = load(v, "background");
        let want = contrastxr::background_preparation::prepare(
            &camera,
            output.width,
            output.height,
            &params,
        );
        let t = f64::from(params.transmittance);
        let mut worst = 0;
        for (got, linear) in output.pixels.iter().zip(&want.linear) {
            let want = contrastxr::colour::linear_to_srgb8(*linear * t);
            for c in 0..3 {
                worst = worst.max((i32::from(got[c]) - i32::from(want[c])).abs());
            }
        }
        assert!(worst <= 2, "view {v}: off by {worst} code values");
        outputs.push(output);
    }
    assert_ne!(
        outputs[0].pixels, outputs[1].pixels,
        "the eyes see different parts"
    );
}
