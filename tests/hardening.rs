//! Hardening and live control, against the real Monado runtime in the sandbox (see
//! tests/common/mod.rs for the skip/require rule): every named fault point leaves the app
//! running with its frames untouched and one log line; broken configs are named by file, line
//! and key while the app runs on; config edits reach a running app; a soak and 100 session
//! cycles under Vulkan (incl. synchronisation) and OpenXR core validation stay clean and flat.
//!
//! "Untouched" is checked by the XR client, not the layer: with --check-untouched it reads
//! each swapchain image back when it gets it again and compares it with what it wrote.
//! The config parser and environment parsing are fuzzed with proptest (no sandbox needed).

mod common;

use common::{
    layer_lines, sandbox, scratch_dir, session_memory, wait_for, ApiDump, SandboxRun, Validation,
    CLI, RUN_TIMEOUT_S, SYNC_VALIDATION, XR_CLIENT,
};
use contrastxr::config::{self, Env, Source, KEYS};
use contrastxr::image::RgbaImage;
use proptest::prelude::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

const SIZE: &str = "64x48";
const APP: &str = "contrastxr-xr-client";

struct LayerRun {
    run: SandboxRun,
    report: Value,
    lines: Vec<String>,
}

impl LayerRun {
    fn modified(&self) -> Vec<u64> {
        self.report["frames_modified"]
            .as_array()
            .expect("frames_modified")
            .iter()
            .filter_map(Value::as_u64)
            .collect()
    }

    fn checked(&self) -> u64 {
        self.report["frames_checked"].as_u64().unwrap_or(0)
    }

    /// The layer's lines that contain `text`.
    fn lines_with(&self, text: &str) -> Vec<&String> {
        self.lines.iter().filter(|l| l.contains(text)).collect()
    }

    #[track_caller]
    fn assert_ran(&self, frames: u64) {
        self.run.assert_success();
        assert_eq!(self.report["ok"], true, "{}", self.run.describe());
        let submitted = self.report["frames_submitted"].as_u64().unwrap_or(0);
        assert!(
            submitted >= frames,
            "{submitted} frames: {}",
            self.run.describe()
        );
    }
}

/// Runs the client through the layer (on, forced: the simulated HMD is OPAQUE) with both
/// validation layers. `config` is the layer's config file (it need not exist).
fn client(tag: &str, config: &Path, env: &[(&str, &str)], args: &[&str]) -> Option<LayerRun> {
    let sandbox = sandbox()?;
    let validation = Validation::new(tag);
    let config = config.to_string_lossy().into_owned();
    let mut all = vec![
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        // Frames are compared with what the app rendered: no indicator text in them.
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_CONFIG", config.as_str()),
    ];
    all.extend(validation.env());
    all.extend(env);
    let mut cmd = vec![XR_CLIENT, "--validation", "--json"];
    cmd.extend(args);
    // 20 Hz, plus start-up and slack for a slow machine.
    let frames: u64 = args
        .windows(2)
        .find(|w| w[0] == "--frames")
        .and_then(|w| w[1].parse().ok())
        .unwrap_or(60);
    let run = sandbox.run_for(&cmd, &all, RUN_TIMEOUT_S + frames / 5);
    validation.assert_clean();
    let report = run.client_report();
    let lines = layer_lines(&run);
    Some(LayerRun { run, report, lines })
}

fn no_config(tag: &str) -> PathBuf {
    scratch_dir(tag).join("absent.toml")
}

fn config_file(tag: &str, text: &str) -> PathBuf {
    let path = scratch_dir(tag).join("config.toml");
    std::fs::write(&path, text).expect("write the config");
    path
}

const CHECKED: &[&str] = &["--frames", "20", "--size", SIZE, "--check-untouched"];

// ---- fault points ----

/// How the fault matrix runs the layer's pipelines: as the other tests do (`wait`: every frame
/// counted), and in the default mode (`background`). There, from an empty shader cache, the
/// points fire while the pipeline thread is still building; the two that only a processed
/// frame reaches (an allocation, a view's copy) run from the tests' warm cache and fire at the
/// first frame whose pipelines are ready.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Pipelines {
    Wait,
    Building,
}

/// The longest call an app may see in a fault run: a frame call that waits for a shader
/// compile, a device teardown or a cache write takes seconds on lavapipe.
const LONGEST_CALL_MS: f64 = 1000.0;

/// The longest xrDestroySession and xrDestroyInstance may take, in every run: a build or a
/// warm-up compile in flight included (docs/layer.md, Teardown).
const TEARDOWN_MS: f64 = 1000.0;

/// Fills the tests' shared shader cache once (a run without faults), so that the `wait` runs
/// and the runs that need built pipelines start from a cache, as the other tests do.
fn warm_shared_cache() -> Option<()> {
    static WARM: std::sync::Mutex<bool> = std::sync::Mutex::new(false);
    let mut warm = WARM.lock().unwrap_or_else(|p| p.into_inner());
    if !*warm {
        let r = client("warm-cache", &no_config("warm-cache"), &[], CHECKED)?;
        r.assert_ran(20);
        *warm = true;
    }
    Some(())
}

/// A fault run's client, with the pipelines as `mode` says.
fn fault_client(tag: &str, point: &str, mode: Pipelines) -> Option<LayerRun> {
    let after_build = ["allocation", "image-capture"].contains(&point);
    if mode == Pipelines::Wait || after_build {
        warm_shared_cache()?;
    }
    let tag = format!("{tag}-{mode:?}").to_lowercase();
    let cache = scratch_dir(&format!("{tag}-cache"));
    let cache = cache.to_string_lossy().into_owned();
    let mut env = vec![("CONTRASTXR_FAULT", point)];
    let mut args = [CHECKED, &["--timing", "--exit-marker"][..]].concat();
    if mode == Pipelines::Building {
        env.push(("CONTRASTXR_PIPELINES", "background"));
        match after_build {
            true => args[1] = "60",
            false => env.push(("XDG_CACHE_HOME", cache.as_str())),
        }
    }
    let r = client(&tag, &no_config(&tag), &env, &args)?;
    let longest = longest_call_ms(&r.report);
    eprintln!("{tag}: longest frame-loop call {longest:.1} ms");
    // In mode `wait` the first enhanced frame waits for its pipelines by design (a cache
    // load and, on a CPU driver, the compile at first dispatch): the bound is the default
    // mode's, where no app call may wait for the layer's pipelines.
    assert!(
        mode == Pipelines::Wait || longest < LONGEST_CALL_MS,
        "{tag}: a frame-loop call took {longest:.1} ms: {}",
        r.report["timing"]["calls"]
    );
    assert_teardown_bounded(&tag, &r.report);
    r.run.assert_success();
    common::assert_exit_waits_first(&tag, &r.run.stderr);
    Some(r)
}

/// xrDestroySession and xrDestroyInstance each returned within [`TEARDOWN_MS`].
fn assert_teardown_bounded(tag: &str, report: &Value) {
    let teardown = &report["teardown_ms"];
    for call in ["xrDestroySession", "xrDestroyInstance"] {
        let ms = teardown[call]
            .as_f64()
            .unwrap_or_else(|| panic!("{tag}: {teardown}"));
        eprintln!("{tag}: {call} {ms:.1} ms");
        assert!(ms < TEARDOWN_MS, "{tag}: {call} took {ms:.1} ms");
    }
}

/// The longest of the client's frame-loop calls (`--timing`).
fn longest_call_ms(report: &Value) -> f64 {
    let calls = report["timing"]["calls"].as_object().expect("timing.calls");
    calls
        .values()
        .filter_map(|c| c["max_ms"].as_f64())
        .fold(0.0, f64::max)
}

/// A fault point, in both pipeline modes: the app runs to its end with no frame-loop call
/// near a second, no frame is changed (for the mid-stream ones: none after the fault), and the
/// layer says so in exactly one line.
fn fault(point: &str, says: &str) {
    for mode in [Pipelines::Wait, Pipelines::Building] {
        let tag = format!("fault-{}", point.replace('@', "-"));
        let Some(r) = fault_client(&tag, point, mode) else {
            return;
        };
        r.assert_ran(20);
        assert!(r.checked() >= 10, "{} images checked", r.checked());
        let modified = r.modified();
        if point.starts_with("camera-loss") {
            // Frames before the loss were enhanced (once the pipelines were ready); none after.
            let some = mode == Pipelines::Building || !modified.is_empty();
            assert!(some && modified.iter().all(|&f| f < 10), "{modified:?}");
        } else {
            assert!(modified.is_empty(), "frames changed: {modified:?}");
        }
        let about = r.lines_with("passing");
        assert_eq!(
            about.len(),
            1,
            "{mode:?}: {about:#?}; all lines: {:#?}",
            r.lines
        );
        assert!(about[0].contains(says), "{mode:?}: {about:?}");
    }
}

#[test]
fn fault_at_device_setup() {
    fault("device-setup", "fault injected at device-setup");
}

#[test]
fn fault_at_pipeline_creation() {
    fault("pipeline-creation", "fault injected at pipeline-creation");
}

/// A panic while a pipeline builds fails its slot (the session passes through, one line), and
/// the build is no longer counted as in progress.
#[test]
fn a_panic_in_a_build_fails_its_pipeline() {
    fault("build-panic", "internal error building the");
}

#[test]
fn an_app_queue_without_compute_passes_through() {
    fault("queue-without-compute", "has no compute support");
}

#[test]
fn fault_at_allocation() {
    fault("allocation", "fault injected at allocation");
}

#[test]
fn fault_at_image_capture() {
    fault("image-capture", "fault injected at image-capture");
}

#[test]
fn fault_at_camera_open() {
    fault("camera-open", "fault injected at camera-open");
}

#[test]
fn fault_at_mid_stream_camera_loss() {
    fault("camera-loss@5", "lost: passing frames through");
}

/// A panic in the layer's xrEndFrame, after it enhanced and held the frame's images: the app's
/// frame still reaches the runtime (every frame is submitted, the images released), the
/// frames before it were enhanced (once the pipelines were ready) and none after, and the
/// layer says so once, in both pipeline modes.
#[test]
fn a_panic_in_end_frame_still_forwards_the_frame() {
    for mode in [Pipelines::Wait, Pipelines::Building] {
        let Some(r) = fault_client("fault-end-frame", "end-frame@5", mode) else {
            return;
        };
        r.assert_ran(20);
        let modified = r.modified();
        let some = mode == Pipelines::Building || !modified.is_empty();
        assert!(some && modified.iter().all(|&f| f <= 5), "{modified:?}");
        let about = r.lines_with("passing");
        assert_eq!(about.len(), 1, "{about:#?}");
        assert!(
            about[0].contains("internal error in xrEndFrame"),
            "{about:?}"
        );
    }
}

/// A panic in the layer's own part of xrDestroySwapchain, xrDestroySession and
/// xrDestroyInstance still forwards each call: api_dump, below the layer, sees the runtime get
/// every one of them, and the app ends cleanly.
#[test]
fn destroy_calls_reach_the_runtime_after_a_panic() {
    let tag = "fault-destroy-bookkeeping";
    let Some(sandbox) = sandbox() else { return };
    let dump = ApiDump::new(tag);
    let mut env = vec![
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_FAULT", "destroy-bookkeeping"),
        ("XR_ENABLE_API_LAYERS", ApiDump::LAYER),
    ];
    env.extend(dump.env());
    let run = sandbox.run(
        &[XR_CLIENT, "--json", "--frames", "10", "--size", SIZE],
        &env,
    );
    run.assert_success();
    let lines = layer_lines(&run);
    for call in [
        "xrDestroySwapchain",
        "xrDestroySession",
        "xrDestroyInstance",
    ] {
        assert_eq!(dump.calls(call).len(), 1, "{call}: {lines:#?}");
        let said = format!("internal error in {call}: fault injected");
        assert_eq!(
            lines.iter().filter(|l| l.contains(&said)).count(),
            1,
            "{lines:#?}"
        );
    }
}

/// A shader compile that outlasts every wait of the session's end (`slow-build`: each warm-up
/// compile takes 5 s more) from an empty cache: the session ends after 20 frames while the
/// first compile runs, xrDestroySession and xrDestroyInstance return within 1 s (the compile
/// finishes on a thread of its own), the app's exit waits for it first of all (said once),
/// and the app exits 0 with its frames untouched.
#[test]
fn teardown_with_a_build_in_flight_is_bounded() {
    let tag = "fault-slow-build";
    let Some(r) = fault_client(tag, "slow-build", Pipelines::Building) else {
        return;
    };
    r.assert_ran(20);
    assert!(r.modified().is_empty(), "{:?}", r.modified());
    let reached = r.lines_with("fault point slow-build reached");
    assert_eq!(
        reached,
        ["fault point slow-build reached 1 times"],
        "{:#?}",
        r.lines
    );
    let waited = r.lines_with("the app's exit waited");
    assert_eq!(waited.len(), 1, "{:#?}", r.lines);
}

/// A CPU driver's warm-up device that cannot be made is tried once per session, not in every
/// frame call, and said in one line.
#[test]
fn a_failed_warm_up_device_is_tried_once() {
    let tag = "fault-warm-up-device";
    let env = [("CONTRASTXR_FAULT", "warm-up-device")];
    let Some(r) = client(tag, &no_config(tag), &env, CHECKED) else {
        return;
    };
    r.assert_ran(20);
    let said = r.lines_with("no warm-up device (fault injected at warm-up-device");
    assert_eq!(said.len(), 1, "{:#?}", r.lines);
    let reached = r.lines_with("fault point warm-up-device reached");
    assert_eq!(reached, ["fault point warm-up-device reached 1 times"]);
}

/// A `video:` background of `frames` 640x480 frames at 100 Hz (a y4m file, 4:2:0), each a
/// different grey: its thread prepares a new frame's texels every 10 ms.
fn fast_video(tag: &str, frames: u8) -> PathBuf {
    let path = scratch_dir(tag).join("fast.y4m");
    let (w, h) = (640, 480);
    let mut bytes = format!("YUV4MPEG2 W{w} H{h} F100:1 C420jpeg\n").into_bytes();
    for i in 0..frames {
        bytes.extend_from_slice(b"FRAME\n");
        bytes.extend(std::iter::repeat_n(40 + i * 20, w * h));
        bytes.extend(std::iter::repeat_n(128, w * h / 2));
    }
    std::fs::write(&path, bytes).expect("write the video");
    path
}

/// The fence wait at xrDestroySession fails (VK_ERROR_DEVICE_LOST) while a live background
/// writes its texels into the layer's mapped images, and the app destroys its device right
/// after xrDestroySession and runs on: the layer closed those images to the source's thread
/// first, so no run crashes on a write into freed memory (10 of 10).
#[test]
fn a_lost_device_at_session_end_leaves_no_writer() {
    let tag = "fault-device-lost";
    let Some(sandbox) = sandbox() else { return };
    let video = format!("video:{}", fast_video(tag, 8).display());
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", video.as_str()),
        ("CONTRASTXR_FAULT", "device-lost"),
    ];
    let cmd = [XR_CLIENT, "--json", "--frames", "30", "--size", SIZE];
    let cmd = [&cmd[..], &["--after-device-ms", "500"]].concat();
    for i in 0..10 {
        let run = sandbox.run(&cmd, &env);
        assert!(run.status.success(), "run {i}: {}", run.describe());
        let lines = layer_lines(&run);
        let said = "did not finish the layer's last work (vkWaitForFences failed";
        assert_eq!(
            lines.iter().filter(|l| l.contains(said)).count(),
            1,
            "{lines:#?}"
        );
    }
}

/// The fence wait in xrDestroySwapchain fails: the app's image views stay alive, keyed by
/// handles the runtime may give out again, so the session passes through from then on (one
/// line), never enhancing a later swapchain through a stale view. Without Vulkan validation:
/// a churn thread shares the app's queue with Monado's swapchain calls (tests/startup.rs).
#[test]
fn a_failed_wait_at_swapchain_destroy_retires_the_session() {
    let Some(sandbox) = sandbox() else { return };
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_FAULT", "swapchain-wait"),
    ];
    let cmd = [&[XR_CLIENT, "--json"][..], CHECKED, &["--churn-swapchains"]].concat();
    let run = sandbox.run(&cmd, &env);
    run.assert_success();
    let lines = layer_lines(&run);
    let about: Vec<_> = lines.iter().filter(|l| l.contains("passing")).collect();
    assert_eq!(about.len(), 1, "{lines:#?}");
    assert!(about[0].contains("xrDestroySwapchain"), "{about:?}");
    let report = run.client_report();
    let modified = report["frames_modified"]
        .as_array()
        .expect("frames_modified");
    assert!(
        modified.iter().all(|f| f.as_u64() < Some(10)),
        "{modified:?}"
    );
}

/// An app whose stderr is a full pipe nobody reads, with debug logging: no frame-loop call
/// waits for the layer's log lines (each under 100 ms over 600 frames).
#[test]
fn logging_never_blocks_the_app() {
    let tag = "stderr-full";
    let env = [
        ("CONTRASTXR_LOG", "debug"),
        ("CONTRASTXR_PIPELINES", "background"),
    ];
    let args = [
        "--frames",
        "600",
        "--size",
        SIZE,
        "--timing",
        "--stderr-full",
    ];
    let Some(r) = client(tag, &no_config(tag), &env, &args) else {
        return;
    };
    r.assert_ran(600);
    // The calls the layer intercepts (it logs in no other): xrWaitFrame and xrBeginFrame are
    // the runtime's alone, and xrWaitFrame's pacing wait swings on a loaded machine.
    let calls = r.report["timing"]["calls"]
        .as_object()
        .expect("timing.calls");
    let longest = calls
        .iter()
        .filter(|(name, _)| !["xrWaitFrame", "xrBeginFrame"].contains(&name.as_str()))
        .filter_map(|(_, c)| c["max_ms"].as_f64())
        .fold(0.0, f64::max);
    eprintln!("longest call the layer intercepts: {longest:.1} ms");
    assert!(longest < 100.0, "{}", r.report["timing"]["calls"]);
}

/// A log folder the layer cannot write is said once on stderr, with the path and why, and the
/// app runs on: a path under /dev/null, and a FIFO nobody reads where the log file would be
/// (opening it for writing would block for ever).
#[test]
fn an_unwritable_log_file_is_said_once_and_never_blocks() {
    let Some(sandbox) = sandbox() else { return };
    let dir = scratch_dir("log-fifo");
    std::fs::create_dir_all(dir.join("contrastxr")).unwrap();
    let fifo = dir.join("contrastxr/layer.log");
    let status = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(
        status.is_ok_and(|s| s.success()),
        "mkfifo {}",
        fifo.display()
    );
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
    ];
    let fifo_home = format!("XDG_STATE_HOME={}", dir.display());
    let cases = [
        (
            "XDG_STATE_HOME=/dev/null",
            "cannot create /dev/null/contrastxr",
        ),
        (fifo_home.as_str(), "layer.log"),
    ];
    for (state_home, why) in cases {
        // The sandbox passes no XDG_STATE_HOME: it goes on the command line.
        let cmd = [
            "/usr/bin/env",
            state_home,
            XR_CLIENT,
            "--json",
            "--frames",
            "5",
        ];
        let run = sandbox.run(&[&cmd[..], &["--size", SIZE]].concat(), &env);
        run.assert_success();
        let lines = layer_lines(&run);
        let said: Vec<_> = lines.iter().filter(|l| l.contains("log file")).collect();
        assert_eq!(said.len(), 1, "{state_home}: {lines:#?}");
        assert!(said[0].contains(why), "{state_home}: {said:?}");
    }
}

/// The layer takes the app's Vulkan functions from the app's own vkGetInstanceProcAddr (given
/// with XR_KHR_vulkan_enable2): the client's counting one is called inside xrCreateSession
/// more with the layer on than off.
#[test]
fn the_layer_uses_the_apps_own_vulkan() {
    let Some(sandbox) = sandbox() else { return };
    let calls = |on: &str| {
        let env = [
            ("CONTRASTXR", on),
            ("CONTRASTXR_FORCE", "1"),
            ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ];
        let run = sandbox.run(
            &[XR_CLIENT, "--json", "--frames", "5", "--size", SIZE],
            &env,
        );
        run.assert_success();
        let report = run.client_report();
        report["vk_gipa_calls_in_create_session"]
            .as_u64()
            .expect("vk_gipa_calls_in_create_session")
    };
    let (off, on) = (calls("0"), calls("1"));
    assert!(on > off, "layer off: {off} calls, on: {on}");
}

/// More view regions in one frame than the layer keeps buffers for (2 projection views and 20
/// quad layers, one per strip of the quad's image): every frame is enhanced, nothing fails.
#[test]
fn any_number_of_regions_per_frame_is_enhanced() {
    let tag = "many-regions";
    let env = [("CONTRASTXR_QUAD_LAYERS", "1")];
    let args = [CHECKED, &["--quad", "--quad-strips", "20"][..]].concat();
    let Some(r) = client(tag, &no_config(tag), &env, &args) else {
        return;
    };
    r.assert_ran(20);
    assert!(r.lines_with("passing").is_empty(), "{:#?}", r.lines);
    assert!(
        r.modified().len() as u64 + 2 >= r.checked(),
        "{:?} of {}",
        r.modified(),
        r.checked()
    );
}

/// A session the layer does not act on (the simulated display is OPAQUE, not forced) never
/// opens its background: the camera-open fault point is never reached.
#[test]
fn the_background_opens_only_for_frames_the_layer_acts_on() {
    let tag = "no-open-when-opaque";
    let env = [
        ("CONTRASTXR_FORCE", "0"),
        ("CONTRASTXR_FAULT", "camera-open"),
    ];
    let Some(r) = client(tag, &no_config(tag), &env, CHECKED) else {
        return;
    };
    r.assert_ran(20);
    assert!(r.modified().is_empty(), "{:?}", r.modified());
    assert!(r.lines_with("camera-open").is_empty(), "{:#?}", r.lines);
    assert_eq!(r.lines_with("is not ADDITIVE").len(), 1, "{:#?}", r.lines);
}

/// The untouched check can fail: without a fault the layer changes the frames.
#[test]
fn without_a_fault_frames_are_enhanced() {
    let tag = "no-fault";
    let Some(r) = client(tag, &no_config(tag), &[], CHECKED) else {
        return;
    };
    r.assert_ran(20);
    assert!(
        r.modified().len() as u64 + 2 >= r.checked(),
        "{:?}",
        r.report
    );
    assert!(r.lines_with("passing").is_empty(), "{:?}", r.lines);
}

#[test]
fn mode_off_does_no_gpu_work() {
    let tag = "mode-off";
    let env = [("CONTRASTXR_MODE", "off")];
    let Some(r) = client(tag, &no_config(tag), &env, CHECKED) else {
        return;
    };
    r.assert_ran(20);
    assert!(
        r.checked() >= 10 && r.modified().is_empty(),
        "{:?}",
        r.report
    );
    assert!(
        r.lines_with("processing frames").is_empty(),
        "{:?}",
        r.lines
    );
}

// ---- broken configs ----

#[test]
fn corrupt_config_is_named_and_ignored() {
    let path = config_file("corrupt", "lambda_e = 0.6\n[app.\"x\"\nmode = \"off\"\n");
    let Some(r) = client("corrupt", &path, &[], CHECKED) else {
        return;
    };
    r.assert_ran(20);
    let named = r.lines_with(&format!("config {}:2: not valid TOML", path.display()));
    assert_eq!(named.len(), 1, "{:#?}", r.lines);
    assert_eq!(
        r.lines_with(&path.display().to_string()).len(),
        2,
        "{:#?}",
        r.lines
    );
    assert!(
        r.lines
            .contains(&"setting lambda_e = 0.4  # default".to_string()),
        "{:#?}",
        r.lines
    );
    assert!(
        !r.modified().is_empty(),
        "the layer runs on with the defaults"
    );
}

#[test]
fn wrong_types_are_named_by_file_line_and_key() {
    let text = "lambda_e = \"high\"\nmode = 3\nblur_size = 4\ntransmittance = 0.3\n\
                [app.\"contrastxr-xr-client\"]\nfov = \"yes\"\n";
    let path = config_file("wrong-types", text);
    let Some(r) = client("wrong-types", &path, &[], CHECKED) else {
        return;
    };
    r.assert_ran(20);
    let p = path.display();
    for (line, key) in [(1, "lambda_e"), (2, "mode"), (3, "blur_size"), (6, "fov")] {
        let named = r.lines_with(&format!("config {p}:{line}: {key}: "));
        assert_eq!(named.len(), 1, "{key}: {:#?}", r.lines);
        assert!(named[0].contains(&format!("{key} stays")), "{named:?}");
    }
    let setting = format!("setting transmittance = 0.3  # {p}:4");
    assert!(r.lines.contains(&setting), "{:#?}", r.lines);
    assert!(r
        .lines
        .contains(&"setting blur_size = 3  # default".to_string()));
    assert!(!r.modified().is_empty(), "the layer runs on");
}

/// The app's own table (by its applicationName) overrides the top level.
#[test]
fn app_table_turns_one_app_off() {
    let text = format!("mode = \"enhance\"\n[app.\"{APP}\"]\nmode = \"off\"\n");
    let path = config_file("app-table", &text);
    let Some(r) = client("app-table", &path, &[], CHECKED) else {
        return;
    };
    r.assert_ran(20);
    assert!(r.modified().is_empty(), "{:?}", r.report);
    let setting = format!(
        "setting mode = \"off\"  # {} [app.\"{APP}\"]:3",
        path.display()
    );
    assert!(r.lines.contains(&setting), "{:#?}", r.lines);
}

// ---- live control ----

fn cli(config: &Path, args: &[&str]) -> (SystemTime, String) {
    let out = std::process::Command::new(CLI)
        .args(args)
        .env("CONTRASTXR_CONFIG", config)
        .output()
        .expect("run contrastxr");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        SystemTime::now(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

fn capture_lambda(json: &Path) -> f64 {
    let text = std::fs::read_to_string(json).expect("capture json");
    let v: Value = serde_json::from_str(&text).expect("capture json parses");
    v["params"]["lambda_e"].as_f64().expect("lambda_e")
}

fn differs(dir: &Path, frame: u64) -> bool {
    let png = |kind: &str| {
        RgbaImage::load_png(&dir.join(format!("frame-{frame}-view-0-{kind}.png")))
            .expect("capture png")
    };
    png("display").pixels != png("output").pixels
}

/// `contrastxr set` changes a running app's output within a second (seen in the captured
/// pixels), and `contrastxr toggle` then turns it off (seen by the client's own check).
#[test]
fn config_edits_reach_a_running_app() {
    if sandbox().is_none() {
        return;
    }
    let dir = scratch_dir("live-edit");
    let config = dir.join("config.toml");
    std::fs::write(&config, "lambda_e = 0.0\n").expect("write the config");
    let capture = dir.join("capture");
    let capture_s = capture.to_string_lossy().into_owned();
    let env = [
        ("CONTRASTXR_CAPTURE_DIR", capture_s.as_str()),
        ("CONTRASTXR_CAPTURE_FRAMES", "100000"),
    ];
    let args = ["--frames", "120", "--size", SIZE, "--check-untouched"];
    let (r, set_at, toggled_at) = std::thread::scope(|s| {
        let run = s.spawn(|| client("live-edit", &config, &env, &args));
        assert!(wait_for(
            &capture.join("frame-5-view-0.json"),
            Duration::from_secs(60)
        ));
        let (set_at, out) = cli(&config, &["set", "lambda_e", "0.6"]);
        assert!(out.starts_with("lambda_e = 0.6"), "{out}");
        std::thread::sleep(Duration::from_secs(2));
        let (toggled_at, out) = cli(&config, &["toggle"]);
        assert!(out.starts_with("mode = \"off\""), "{out}");
        (run.join().expect("client thread"), set_at, toggled_at)
    });
    let Some(r) = r else { return };
    r.assert_ran(120);
    // Pixels: unchanged at lambda_e 0, changed at 0.6.
    assert!(
        !differs(&capture, 1),
        "lambda_e 0 must leave the frame as it is"
    );
    let frames: Vec<(u64, f64, SystemTime)> = (0..)
        .map(|f| (f, capture.join(format!("frame-{f}-view-0.json"))))
        .take_while(|(_, p)| p.exists())
        .map(|(f, p)| {
            (
                f,
                capture_lambda(&p),
                p.metadata().unwrap().modified().unwrap(),
            )
        })
        .collect();
    let first_new = frames
        .iter()
        .find(|(_, l, _)| *l > 0.5)
        .expect("a frame at 0.6");
    assert!(
        differs(&capture, first_new.0),
        "lambda_e 0.6 changes the frame"
    );
    let delay = first_new.2.duration_since(set_at).unwrap_or_default();
    assert!(delay < Duration::from_secs(1), "applied after {delay:?}");
    let reloaded = r.lines_with("reloaded: lambda_e 0 -> 0.6");
    assert_eq!(reloaded.len(), 1, "{:#?}", r.lines);
    // After the toggle nothing is processed: the last capture is from before it, and the
    // client's own check sees no change in the frames of the last second.
    let last = frames.last().expect("captures");
    assert!(
        last.2 < toggled_at + Duration::from_secs(1),
        "captured after toggle"
    );
    let modified = r.modified();
    let submitted = r.report["frames_submitted"].as_u64().unwrap();
    assert!(modified.iter().all(|&f| f + 20 < submitted), "{modified:?}");
}

// ---- soak and session cycles ----

/// `CONTRASTXR_SOAK_FRAMES` (default 1000; the README gives the 10,000-frame command).
fn soak_frames() -> String {
    std::env::var("CONTRASTXR_SOAK_FRAMES").unwrap_or_else(|_| "1000".into())
}

#[test]
fn soak_with_vulkan_sync_and_openxr_validation() {
    let tag = "soak";
    let frames = soak_frames();
    let args = ["--frames", frames.as_str()];
    let Some(r) = client(tag, &no_config(tag), &[SYNC_VALIDATION], &args) else {
        return;
    };
    r.assert_ran(frames.parse().unwrap());
    assert_eq!(r.lines_with("processing frames").len(), 1, "{:#?}", r.lines);
    assert!(r.lines_with("passing").is_empty(), "{:#?}", r.lines);
    // Warm-up: the first 200 frames.
    let memory = session_memory::samples(&r.report, "memory");
    let (warm, end) = (memory[3], *memory.last().unwrap());
    eprintln!(
        "soak: rss {} KiB after 200 frames, {} KiB at the end; heap in use {} and {} KiB",
        warm.rss_kb, end.rss_kb, warm.heap_kb, end.heap_kb
    );
    assert!(
        end.rss_kb < warm.rss_kb + 1024,
        "resident memory grew: {memory:?}"
    );
    // The heap in use tells a leak that resident memory hides (tests/common/session_memory.rs):
    // 2-3 KiB over 800 frames here; a leak of 320 bytes per frame fails, by the least of the
    // last four samples (a sample may fall on a moment's allocations).
    let late = memory.iter().rev().take(4).map(|s| s.heap_kb).min();
    assert!(
        late < Some(warm.heap_kb + 256),
        "the heap in use grew: {memory:?}"
    );
    assert_eq!(warm.fds, end.fds, "file descriptors: {memory:?}");
}

#[test]
fn hundred_session_cycles_leak_nothing() {
    let tag = "cycles";
    let args = ["--sessions", "100", "--frames", "2", "--size", SIZE];
    // glibc gives threads their own malloc arenas (up to 8 per core), and each arena keeps its
    // high-water mark: with the default, resident memory here climbs about 20 MiB per session
    // for 5 to 30 sessions, as new threads (the driver's, the layer's builds) land on unused
    // arenas, then swings by up to 7 MiB between sessions. That hid a leak's growth in noise
    // (CI once counted 13,500 / 2,128 / 1,212 KiB over three runs of 25 sessions on a flat
    // curve). Two arenas leave the curve flat from the fifth session on. The heap in use
    // (tests/common/session_memory.rs) is what tells a leak.
    let env = [SYNC_VALIDATION, ("MALLOC_ARENA_MAX", "2")];
    let Some(r) = client(tag, &no_config(tag), &env, &args) else {
        return;
    };
    r.assert_ran(200);
    assert_eq!(r.report["sessions_run"], 100);
    assert_eq!(
        r.lines_with("session on Vulkan device").len(),
        100,
        "the layer ran each time"
    );
    // Leaks of the layer's own objects are also caught by the validation layer's
    // undestroyed-object report (`sync_validation_and_leak_reports_are_on`).
    session_memory::assert_flat("cycles", &session_memory::samples(&r.report, "sessions"));
}

/// The checks above rely on these: synchronisation validation is really on with
/// [`SYNC_VALIDATION`], and undestroyed objects are reported when the device is destroyed.
#[test]
fn sync_validation_and_leak_reports_are_on() {
    let Some(sandbox) = sandbox() else { return };
    for (flag, seen) in [
        ("--provoke-vk-sync-hazard", "SYNC-HAZARD-WRITE-AFTER-WRITE"),
        ("--provoke-vk-leak", "VUID-vkDestroyDevice-device-05137"),
    ] {
        let validation = Validation::new(&format!("provoke{flag}"));
        let env = [validation.env(), vec![SYNC_VALIDATION]].concat();
        let run = sandbox.run(&[XR_CLIENT, "--validation", "--frames", "2", flag], &env);
        assert!(!run.success(), "{flag} must fail the client");
        let errors = validation.vk_errors();
        assert!(
            errors.iter().any(|e| e.contains(seen)),
            "{flag}: {errors:?}"
        );
    }
}

// ---- parsing never panics ----

fn resolve_text(text: &str, app: &str) {
    let source = Source {
        path: Path::new("/fuzz.toml"),
        text,
    };
    let r = config::resolve(app, Some(source), &Env::default());
    for i in 0..KEYS.len() {
        let _ = r.line(i);
    }
    let _ = config::check(source);
}

fn toml_fragment() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|f| format!("{f:?}")),
        any::<i64>().prop_map(|i| i.to_string()),
        any::<bool>().prop_map(|b| b.to_string()),
        ".{0,12}".prop_map(|s| format!("{s:?}")),
        Just("nan".to_string()),
        Just("-inf".to_string()),
        Just("[1, 2]".to_string()),
        Just("[1e40, -0.0]".to_string()),
        Just("{ a = 1 }".to_string()),
        Just("1979-05-27T07:32:00Z".to_string()),
        Just("[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1".to_string()),
    ]
}

fn toml_line() -> impl Strategy<Value = String> {
    let key = prop_oneof![
        proptest::sample::select(KEYS.iter().map(|k| k.name).collect::<Vec<_>>())
            .prop_map(String::from),
        "[a-z_.\"]{1,10}",
    ];
    prop_oneof![
        (key, toml_fragment()).prop_map(|(k, v)| format!("{k} = {v}")),
        Just("[app.\"a\"]".to_string()),
        Just("[app]".to_string()),
        Just("[[app]]".to_string()),
        "\\[[a-z.\"]{0,8}\\]",
    ]
}

proptest! {
    // scripts/fuzz makes a longer run through CONTRASTXR_FUZZ_CASES (and PROPTEST_RNG_SEED).
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("CONTRASTXR_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(512)
    ))]

    #[test]
    fn config_parser_never_panics_on_any_text(text in "\\PC{0,200}") {
        resolve_text(&text, "a");
    }

    #[test]
    fn config_parser_never_panics_on_toml_like_text(lines in proptest::collection::vec(toml_line(), 0..12)) {
        resolve_text(&lines.join("\n"), "a");
    }

    #[test]
    fn environment_parsing_never_panics(values in proptest::collection::vec((0..KEYS.len(), "\\PC{0,24}"), 0..8)) {
        let pairs: Vec<(&str, &str)> = values.iter().map(|(i, v)| (KEYS[*i].env, v.as_str())).collect();
        let r = config::resolve("a", None, &Env::from_pairs(pairs));
        prop_assert!(r.settings.params.validate().is_ok());
    }

    #[test]
    fn cli_values_never_panic(i in 0..KEYS.len(), text in "\\PC{0,24}") {
        let key = &KEYS[i];
        if let Ok(v) = key.parse_setting(&text) {
            let mut s = config::Settings::default();
            if key.apply(&mut s, v).is_ok() {
                prop_assert!(s.params.validate().is_ok());
            }
        }
    }
}

/// The commented example config in the repository is valid and shows every key.
#[test]
fn example_config_is_valid_and_complete() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("contrastxr.example.toml");
    let text = std::fs::read_to_string(&path).expect("contrastxr.example.toml");
    let problems = config::check(Source {
        path: &path,
        text: &text,
    });
    assert!(problems.is_empty(), "{problems:#?}");
    for key in KEYS {
        assert!(
            text.contains(&format!("\n{} = ", key.name)),
            "{} is not shown",
            key.name
        );
        assert!(text.contains(key.env), "{} is not named", key.env);
    }
    // Its top-level values are the defaults.
    let r = config::resolve(
        "",
        Some(Source {
            path: &path,
            text: &text,
        }),
        &Env::default(),
    );
    assert_eq!(r.settings, config::Settings::default());
}

/// Captures are written off the app's thread: with every capture file's creation stalled 2 s
/// (`stalled-file-system`, a hung mount under the capture folder), no frame-loop call nears a
/// second, the session's end stays bounded, and the exit waits at most 5 s for the captures
/// still waiting, saying so in one line.
#[test]
fn captures_on_a_stalled_file_system_never_hold_a_frame() {
    let tag = "stalled-captures";
    warm_shared_cache();
    let capture = scratch_dir(tag).join("capture");
    let capture_s = capture.to_string_lossy().into_owned();
    let env = [
        ("CONTRASTXR_FAULT", "stalled-file-system"),
        ("CONTRASTXR_PIPELINES", "background"),
        ("CONTRASTXR_CAPTURE_DIR", capture_s.as_str()),
        ("CONTRASTXR_CAPTURE_FRAMES", "2"),
    ];
    let args = ["--frames", "60", "--size", SIZE, "--timing"];
    let Some(r) = client(tag, &no_config(tag), &env, &args) else {
        return;
    };
    r.assert_ran(60);
    let longest = longest_call_ms(&r.report);
    eprintln!("{tag}: longest frame-loop call {longest:.1} ms");
    assert!(
        longest < LONGEST_CALL_MS,
        "a frame-loop call took {longest:.1} ms: {}",
        r.report["timing"]["calls"]
    );
    assert_teardown_bounded(tag, &r.report);
    assert!(
        !r.lines_with("processing frames").is_empty(),
        "{:#?}",
        r.lines
    );
    let left = r.lines_with("exiting with captures not yet written");
    assert_eq!(left.len(), 1, "{:#?}", r.lines);
}

/// With `pipelines = "wait"` the frame call waits for the background to open 1 s at most: an
/// `image:` background on a stalled file system (`stalled-file-system`: its look-up takes 2 s,
/// as under a hung mount) leaves no frame-loop call at 1.6 s or more, and says once that frames
/// pass through until it has opened.
#[test]
fn a_background_on_a_stalled_file_system_holds_a_waiting_frame_at_most_a_second() {
    let tag = "stalled-background-wait";
    warm_shared_cache();
    let picture = scratch_dir(tag).join("background.png");
    let pixels = (0..64 * 48)
        .map(|i| [(i % 251) as u8, 90, 160, 255])
        .collect();
    let image = contrastxr::image::RgbaImage {
        width: 64,
        height: 48,
        pixels,
        has_alpha: false,
    };
    image.save_png(&picture).unwrap();
    let background = format!("image:{}", picture.display());
    let env = [
        ("CONTRASTXR_FAULT", "stalled-file-system"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_BACKGROUND", background.as_str()),
    ];
    let args = ["--frames", "80", "--size", SIZE, "--timing"];
    let Some(r) = client(tag, &no_config(tag), &env, &args) else {
        return;
    };
    r.assert_ran(80);
    let longest = longest_call_ms(&r.report);
    eprintln!("{tag}: longest frame-loop call {longest:.1} ms");
    assert!(
        longest < 1600.0,
        "a frame-loop call took {longest:.1} ms: {}",
        r.report["timing"]["calls"]
    );
    let said = r.lines_with("did not open within 1 s");
    assert_eq!(said.len(), 1, "{:#?}", r.lines);
}
