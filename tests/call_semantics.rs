//! With the layer on, every OpenXR call the app makes gets the answer it gets with the layer off
//! (the real Monado runtime, sandbox). The test client's `--script` mode makes raw swapchain and
//! frame calls in orders the spec names (valid and invalid) and reports each call's XrResult;
//! each script runs with the layer loaded but off (`CONTRASTXR=0`: every call goes straight to
//! the runtime) and on, and the two lists must be equal. With the layer on, the number of
//! frames it enhanced (counted from its captures) must be what the script's released images
//! call for, worked out by hand below: no frame the app released for display is lost.

mod common;

use common::semantics::{
    self, assert_same_answers, capture_paths, enhanced_frames, script_of, Case,
};
use common::{sandbox, scratch_dir, SandboxRun, XR_CLIENT};

/// Runs `script` with the layer off and on (forced on the simulated OPAQUE display); returns
/// both runs and the capture folder.
/// How a case runs: the layer's `in_place` setting and the client's swapchain format (None:
/// the runtime's first, R16G16B16A16_UNORM on Monado, which has no in-place path).
type Variant = (&'static str, Option<&'static str>);

/// The default; in place asked for on an sRGB format (Monado refuses the storage usage and
/// the layer makes the swapchain again from the app's own create info); in place granted.
const VARIANTS: [Variant; 3] = [
    ("auto", None),
    ("on", Some("R8G8B8A8_SRGB")),
    ("on", Some("R8G8B8A8_UNORM")),
];

fn run_both(
    tag: &str,
    script: &str,
    (in_place, format): Variant,
) -> Option<(SandboxRun, SandboxRun, std::path::PathBuf)> {
    let tag = format!("{tag}-{in_place}-{}", format.unwrap_or("default"));
    let switches = [("CONTRASTXR_FORCE", "1"), ("CONTRASTXR_IN_PLACE", in_place)];
    let args: Vec<&str> = format.map_or(Vec::new(), |f| vec!["--format", f]);
    run_both_with(&tag, script, &switches, &args)
}

/// Runs `script` with the layer off and on, `switches` being how the layer is made to act;
/// returns both runs and the capture folder.
fn run_both_with(
    tag: &str,
    script: &str,
    switches: &[(&str, &str)],
    args: &[&str],
) -> Option<(SandboxRun, SandboxRun, std::path::PathBuf)> {
    let sandbox = sandbox()?;
    let mut cmd = vec![
        XR_CLIENT,
        "--json",
        "--validation",
        "--size",
        "64x48",
        "--script",
        script,
    ];
    cmd.extend_from_slice(args);
    let off = sandbox.run(&cmd, &[("CONTRASTXR", "0")]);
    let dir = scratch_dir(&format!("semantics-{tag}"));
    let dir_text = dir.to_string_lossy().into_owned();
    let mut env = vec![
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_CAPTURE_DIR", &dir_text),
        ("CONTRASTXR_CAPTURE_FRAMES", "1000"),
    ];
    env.extend_from_slice(switches);
    let on = sandbox.run(&cmd, &env);
    Some((off, on, dir))
}

/// The case in every variant (VARIANTS): the same answers and enhanced frames on every path.
fn check_case(tag: &str, case: Case) {
    for variant in VARIANTS {
        check_case_with(tag, case, variant);
    }
}

fn check_case_with(tag: &str, case: Case, variant: Variant) {
    let Some((off, on, dir)) = run_both(tag, case.script, variant) else {
        return;
    };
    let bare = assert_same_answers(tag, case, &off, &on);
    assert_eq!(
        enhanced_frames(&dir),
        case.enhanced,
        "{tag}: frames the layer enhanced ({bare:?})\n{}",
        on.stderr
    );
    let expected = match variant {
        ("on", Some("R8G8B8A8_UNORM")) => "in-place",
        // Storage refused (sRGB on Monado), or a format the layer does not view in place.
        ("on", _) => "image-copy",
        _ => "copy",
    };
    for path in capture_paths(&dir) {
        assert_eq!(path, expected, "{tag} {variant:?}");
    }
}

/// One test per case of tests/common/semantics.rs (they run in parallel).
macro_rules! cases {
    ($($name:ident: $case:ident;)*) => {$(
        #[test]
        fn $name() {
            check_case(stringify!($name), semantics::$case);
        }
    )*};
}

cases! {
    release_without_acquire: RELEASE_WITHOUT_ACQUIRE;
    wait_without_acquire: WAIT_WITHOUT_ACQUIRE;
    release_without_wait: RELEASE_WITHOUT_WAIT;
    double_wait: DOUBLE_WAIT;
    double_release: DOUBLE_RELEASE;
    wait_after_release: WAIT_AFTER_RELEASE;
    acquire_past_the_image_count: ACQUIRE_PAST_THE_IMAGE_COUNT;
    release_after_the_next_acquire: RELEASE_AFTER_THE_NEXT_ACQUIRE;
    destroy_with_a_held_image: DESTROY_WITH_A_HELD_IMAGE;
    release_across_a_discarded_frame: RELEASE_ACROSS_A_DISCARDED_FRAME;
    plain_frames: PLAIN_FRAMES;
    pipelined_frames: PIPELINED_FRAMES;
    end_without_release: END_WITHOUT_RELEASE;
    blend_modes_untouched: BLEND_MODES_UNTOUCHED;
    additive_frames_refused: ADDITIVE_FRAMES_REFUSED;
}

/// Runs `script` with the layer off and on with `environment_blend_mode = "additive"` (no
/// force); returns both scripts' results and the frames the layer enhanced.
fn run_additive(tag: &str, script: &str) -> Option<(Vec<String>, Vec<String>, usize)> {
    let switch = ("CONTRASTXR_ENVIRONMENT_BLEND_MODE", "additive");
    let (off, on, dir) = run_both_with(tag, script, &[switch], &[])?;
    Some((script_of(&off), script_of(&on), enhanced_frames(&dir)))
}

/// `RESULT n=COUNT [MODES]` of a blend-modes op.
fn blend_answer(line: &str) -> (String, u32, Vec<String>) {
    let rest = line.split_once(' ').unwrap().1;
    let (result, rest) = rest.split_once(" n=").unwrap();
    let (count, modes) = rest.split_once(' ').unwrap();
    let modes = modes.trim_matches(['[', ']']);
    let modes = modes.split_whitespace().map(String::from).collect();
    (result.to_string(), count.parse().unwrap(), modes)
}

/// The runtime lacks ADDITIVE: with the key, ADDITIVE comes first and the count grows by one in
/// both call forms, a capacity that no longer fits is XR_ERROR_SIZE_INSUFFICIENT with the count
/// written (as the runtime answers a short array), and an invalid view configuration keeps the
/// runtime's error.
#[test]
fn additive_display_lists_additive_first() {
    let script = "blend-count,blend-short,blend-fill,blend-bad-view";
    let Some((off, on, _)) = run_additive("additive-blend", script) else {
        return;
    };
    let (off_count, on_count) = (blend_answer(&off[0]), blend_answer(&on[0]));
    assert_eq!(off_count.0, "SUCCESS", "{off:?}");
    assert!(!off_count.2.contains(&"ADDITIVE".to_string()), "{off:?}");
    assert_eq!(
        on_count,
        ("SUCCESS".into(), off_count.1 + 1, vec![]),
        "{on:?}"
    );
    let (off_fill, on_fill) = (blend_answer(&off[2]), blend_answer(&on[2]));
    let mut wanted = vec!["ADDITIVE".to_string()];
    wanted.extend(off_fill.2.iter().cloned());
    assert_eq!(
        on_fill,
        ("SUCCESS".into(), off_fill.1 + 1, wanted),
        "{on:?}"
    );
    // Capacity 1: the runtime's one mode fits, the layer's two do not.
    assert_eq!(off_fill.1, 1, "the simulated HMD has one mode: {off:?}");
    assert_eq!(blend_answer(&off[1]).0, "SUCCESS");
    assert_eq!(
        blend_answer(&on[1]),
        ("ERROR_SIZE_INSUFFICIENT".into(), 2, vec![]),
        "{on:?}"
    );
    assert!(off[3].contains("ERROR_"), "{off:?}");
    assert_eq!(off[3], on[3]);
}

/// An ADDITIVE frame the runtime refuses is accepted and enhanced (without force) with the key;
/// an OPAQUE frame keeps the runtime's answer and passes through.
#[test]
fn additive_display_accepts_and_enhances_additive_frames() {
    let frame = "begin,acquire,wait,release,";
    let script = format!("{frame}end-additive");
    let Some((off, on, enhanced)) = run_additive("additive-end", &script) else {
        return;
    };
    assert_eq!(
        off[4], "end-additive ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED",
        "{off:?}"
    );
    assert_eq!(on[4], "end-additive SUCCESS", "{on:?}");
    assert_eq!(off[..4], on[..4]);
    assert_eq!(enhanced, 1);
    let script = format!("{frame}end-opaque");
    let Some((off, on, enhanced)) = run_additive("additive-end-opaque", &script) else {
        return;
    };
    assert_eq!(off, on);
    assert_eq!(on[4], "end-opaque SUCCESS", "{on:?}");
    assert_eq!(enhanced, 0);
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
    let run = sandbox.run(&cmd, &env);
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
