//! The layer against its own unloading (Monado sandbox; see tests/common/mod.rs for the
//! skip/require rule): an app creates and destroys instances in turn, each session's
//! background still starting (a camera opening on the reopen helper, or not there yet) or running (a video's
//! player, a `world:` camera) when the session ends, and then runs on. The OpenXR loader closes the layer's
//! library at xrDestroyInstance: the library stays mapped by design (RTLD_NODELETE), and
//! every thread of the layer ends on its own within a second.

mod common;

use common::{layer_lines, sandbox, scratch_dir, XR_CLIENT};
use std::path::{Path, PathBuf};

/// A small `video:` background at 100 Hz (y4m, 4:2:0).
fn video(dir: &Path) -> PathBuf {
    let path = dir.join("fast.y4m");
    let mut bytes = b"YUV4MPEG2 W160 H120 F100:1 C420jpeg\n".to_vec();
    for i in 0..4u8 {
        bytes.extend_from_slice(b"FRAME\n");
        bytes.extend(std::iter::repeat_n(60 + i * 40, 160 * 120));
        bytes.extend(std::iter::repeat_n(128, 160 * 120 / 2));
    }
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn nothing_of_the_layer_outlives_its_instances() {
    let Some(sandbox) = sandbox() else { return };
    let dir = scratch_dir("unload");
    let lib = common::fake_v4l2(&dir);
    let node = dir.join("video7");
    std::fs::write(&node, b"").unwrap();
    let (preload, device) = (
        format!("LD_PRELOAD={}", lib.display()),
        format!("FAKE_V4L2_DEVICE={}", node.display()),
    );
    let camera = format!("v4l2:{}", node.display());
    let video = format!("video:{}", video(&dir).display());
    let panorama = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/background-meadow.png");
    let world = format!("world:{}", panorama.display());
    // The camera twice: slow to open (each session ends while the helper opens it), and
    // absent for the first 700 ms (the first session's open fails, later ones find it).
    let backgrounds = [&camera, &video, &world, &camera];
    for run in 0..10 {
        let background = backgrounds[run % backgrounds.len()];
        let camera_timing = match run % backgrounds.len() {
            3 => "FAKE_V4L2_ABSENT_FOR_MS=700",
            _ => "FAKE_V4L2_OPEN_DELAY_MS=800",
        };
        let env = [
            ("CONTRASTXR", "1"),
            ("CONTRASTXR_FORCE", "1"),
            // The background opens on the reopen helper while frames pass through.
            ("CONTRASTXR_PIPELINES", "background"),
            ("CONTRASTXR_BACKGROUND", background.as_str()),
            // world: films through a camera profile.
            ("CONTRASTXR_CAMERA_FOV", "100,80"),
        ];
        // The camera takes 800 ms to open: each session (5 frames, 250 ms) ends while the
        // helper is still opening it. The stand-in's variables go on the command line.
        let cmd = [
            "/usr/bin/env",
            &preload,
            &device,
            camera_timing,
            XR_CLIENT,
            "--json",
            "--size",
            "64x48",
            "--frames",
            "5",
            "--instances",
            "3",
            "--linger-ms",
            "1000",
        ];
        let out = sandbox.run(&cmd, &env);
        out.assert_success();
        let report = out.client_report();
        let left = &report["after_instances"];
        let lines = layer_lines(&out);
        assert_eq!(
            left["layer_threads"],
            serde_json::json!([]),
            "run {run}: {lines:#?}"
        );
        assert_eq!(left["layer_mapped"], true, "run {run}");
        // The video's and the world's threads ran (the camera is still opening at each end);
        // the camera that appears late is missed first, then opened.
        let opened = lines.iter().any(|l| l.starts_with("background is now"));
        assert!(opened || background == &camera, "run {run}: {lines:#?}");
        if run % backgrounds.len() == 3 {
            let missed = lines.iter().any(|l| l.contains("does not exist"));
            assert!(missed && opened, "run {run}: {lines:#?}");
        }
    }
}
