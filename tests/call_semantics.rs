//! With the layer on, every OpenXR call the app makes gets the answer it gets with the layer off
//! (the real Monado runtime, sandbox). The test client's `--script` mode makes raw swapchain and
//! frame calls in orders the spec names (valid and invalid) and reports each call's XrResult;
//! each script runs with the layer loaded but off (`CONTRASTXR=0`: every call goes straight to
//! the runtime) and on, and the two lists must be equal. With the layer on, the number of
//! frames it enhanced (counted from its captures) must be what the script's released images
//! call for, worked out by hand below: no frame the app released for display is lost.

mod common;

use common::{sandbox, scratch_dir, SandboxRun, XR_CLIENT};
use std::collections::BTreeSet;
use std::path::Path;

/// Runs `script` with the layer off and on; returns both runs and the capture folder.
fn run_both(tag: &str, script: &str) -> Option<(SandboxRun, SandboxRun, std::path::PathBuf)> {
    let sandbox = sandbox()?;
    let cmd = [
        XR_CLIENT,
        "--json",
        "--validation",
        "--size",
        "64x48",
        "--script",
        script,
    ];
    let off = sandbox.run(&cmd, &[("CONTRASTXR", "0")]);
    let dir = scratch_dir(&format!("semantics-{tag}"));
    let dir_text = dir.to_string_lossy().into_owned();
    let on = sandbox.run(
        &cmd,
        &[
            ("CONTRASTXR", "1"),
            ("CONTRASTXR_FORCE", "1"),
            ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
            ("CONTRASTXR_CAPTURE_DIR", &dir_text),
            ("CONTRASTXR_CAPTURE_FRAMES", "1000"),
        ],
    );
    Some((off, on, dir))
}

/// The layer's processed frames, from the capture files' names (`frame-<n>-view-<k>...`).
fn enhanced_frames(dir: &Path) -> usize {
    let frames: BTreeSet<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.strip_prefix("frame-")
                .and_then(|rest| rest.split('-').next())
                .map(String::from)
        })
        .collect();
    frames.len()
}

fn script_of(run: &SandboxRun) -> Vec<String> {
    let report = run.client_report();
    assert_eq!(report["ok"], true, "{}", run.describe());
    report["script"]
        .as_array()
        .unwrap_or_else(|| panic!("no script results: {report}"))
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect()
}

fn check_case(tag: &str, script: &str, must_contain: &str, enhanced: usize) {
    let Some((off, on, dir)) = run_both(tag, script) else {
        return;
    };
    let (bare, layered) = (script_of(&off), script_of(&on));
    assert_eq!(
        bare, layered,
        "{tag}: the layer changed what the calls returned (left: off, right: on)"
    );
    assert_eq!(bare.len(), script.split(',').count(), "{tag}: {bare:?}");
    // The script reached the case it is about (the runtime's answer is the expected one).
    assert!(
        bare.iter().any(|r| r.contains(must_contain)),
        "{tag}: no call answered {must_contain}: {bare:?}"
    );
    assert_eq!(
        enhanced_frames(&dir),
        enhanced,
        "{tag}: frames the layer enhanced ({bare:?})\n{}",
        on.stderr
    );
}

/// One test per case (they run in parallel). Each: the script, a result it must contain,
/// and the frames the layer enhances (why, in the comment).
macro_rules! cases {
    ($($name:ident: $script:literal, $contains:literal, $enhanced:literal;)*) => {$(
        #[test]
        fn $name() {
            check_case(stringify!($name), $script, $contains, $enhanced);
        }
    )*};
}

cases! {
    // Nothing acquired: the runtime refuses; nothing to enhance.
    release_without_acquire: "release", "release ERROR_CALL_ORDER_INVALID", 0;
    wait_without_acquire: "wait", "wait ERROR_CALL_ORDER_INVALID", 0;
    // The first release is refused (not waited); the second is held, then dropped with the
    // swapchain when the script ends (never submitted).
    release_without_wait: "acquire,release,wait,release", "release ERROR_CALL_ORDER_INVALID", 0;
    double_wait: "acquire,wait,wait,release", "wait ERROR_CALL_ORDER_INVALID", 0;
    // The held release goes to the runtime (enhanced) before the second, which it refuses.
    double_release: "acquire,wait,release,release", "release ERROR_CALL_ORDER_INVALID", 1;
    // Waiting again after a (held) release: refused with and without the layer.
    wait_after_release: "acquire,wait,release,wait", "wait ERROR_CALL_ORDER_INVALID", 0;
    // Monado has 3 images: the 4th acquire is refused. The first two releases come while
    // later images are acquired (enhanced at once); the last is held and dropped.
    acquire_past_the_image_count:
        "acquire,acquire,acquire,acquire,wait,release,wait,release,wait,release",
        "acquire ERROR_CALL_ORDER_INVALID", 2;
    release_after_the_next_acquire: "acquire,acquire,wait,release,wait,release", "release SUCCESS", 1;
    // The held image dies with its swapchain; the new swapchain's frame is enhanced.
    destroy_with_a_held_image:
        "begin,acquire,wait,release,destroy,create,acquire,wait,release,end", "destroy SUCCESS", 1;
    // The discarded frame's held image goes (enhanced) when the next is acquired.
    release_across_a_discarded_frame:
        "begin,acquire,wait,release,begin,acquire,wait,release,end", "begin FRAME_DISCARDED", 2;
    plain_frames: "begin,acquire,wait,release,end,begin,acquire,wait,release,end", "end SUCCESS", 2;
    // Each next image is acquired and waited before xrEndFrame of the current frame.
    pipelined_frames:
        "begin,acquire,wait,release,acquire,wait,end,begin,release,acquire,wait,end,begin,release,end",
        "end SUCCESS", 3;
    // A frame ended with the image still acquired: the runtime refuses the layer (not released).
    end_without_release: "begin,acquire,wait,end,release,end-empty", "end ERROR_", 0;
}

/// xrDestroySwapchain on one thread while xrEndFrame runs on another: the layer takes its locks
/// in one order everywhere (session, then swapchain), so neither waits forever. A deadlock shows
/// as the run's time limit. The `release-held` pause point widens the window in which
/// xrEndFrame has listed the swapchains but not yet locked them (with the old order, destroy
/// locked the swapchain and then waited for the session: a deadlock within a few frames).
/// (Vulkan validation stays off here: Monado itself uses the app's
/// queue inside xrCreateSwapchain/xrDestroySwapchain, which the threading checks report with
/// the layer off as well.)
#[test]
fn destroying_swapchains_while_frames_end_never_deadlocks() {
    let Some(sandbox) = sandbox() else { return };
    let cmd = [
        XR_CLIENT,
        "--json",
        "--size",
        "160x120",
        "--frames",
        "100",
        "--churn-swapchains",
    ];
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_FAULT", "release-held"),
    ];
    let run = sandbox.run_for(&cmd, &env, 120);
    assert!(run.success(), "{}", run.describe());
    let report = run.client_report();
    assert!(
        report["swapchains_churned"].as_u64().unwrap() >= 100,
        "too few swapchains destroyed during the frames to race: {report}"
    );
    assert!(
        run.stderr.contains("processing frames"),
        "the layer did not enhance while racing: {}",
        run.describe()
    );
}
