//! The project's client with OpenGL sessions on the EGL binding of XR_MNDX_egl_enable
//! (`--graphics opengl --gl-binding egl`: an EGL 4.5 core context of Mesa's surfaceless
//! platform), through the layer, against the real Monado runtime in the sandbox: the layer
//! enhances the session in the app's EGL context within the CPU reference
//! (tests/common/capture_check.rs); without the layer the client finds its images as written;
//! the app finds the GL state and EGL current surfaces it set before xrEndFrame after it, with
//! the layer enhancing as without it (`--check-gl-state`); and when the layer cannot make the
//! app's EGL context current its frames pass through with one line, every image as the app
//! wrote it. An app whose thread has EGL_OPENGL_ES_API bound (EGL's default) while its OpenGL
//! context is current finds that API bound after every frame the layer enhanced.

mod common;

use common::capture_check::{captures, check_view, sample};
use common::pass_through::{assert_one_retry_line, assert_untouched};
use common::{layer_lines, sandbox, scratch_dir, SandboxRun, XR_CLIENT};

/// Each view's size in these runs.
const VIEW: &str = "96x72";

/// The client with an EGL-bound OpenGL session of 12 frames in GL_SRGB8_ALPHA8 with `extra`
/// arguments (None without the sandbox).
fn client_egl(env: &[(&str, &str)], extra: &[&str]) -> Option<SandboxRun> {
    let sandbox = sandbox()?;
    let mut cmd = vec![
        XR_CLIENT,
        "--graphics",
        "opengl",
        "--gl-binding",
        "egl",
        "--json",
        "--frames",
        "12",
        "--size",
        VIEW,
        "--format",
        "R8G8B8A8_SRGB",
    ];
    cmd.extend_from_slice(extra);
    let run = sandbox.run_x11(&cmd, env);
    run.assert_success();
    assert_eq!(
        run.client_report()["gl_binding"],
        "egl",
        "{}",
        run.describe()
    );
    Some(run)
}

/// The client with `env`, its images read back at each next acquire: every one as the app
/// wrote it.
fn untouched(env: &[(&str, &str)]) -> Option<SandboxRun> {
    let run = client_egl(env, &["--check-untouched"])?;
    assert_untouched(&run);
    Some(run)
}

/// With the layer on, the session on the app's EGL context is enhanced: both views of two
/// frames within the CPU reference and visibly changed, captured as OpenGL views.
#[test]
fn egl_sessions_are_enhanced_within_the_reference() {
    let dir = scratch_dir("opengl-egl-enhanced");
    let background = format!("image:{}", sample("background-meadow.png"));
    let dir_text = dir.to_string_lossy().into_owned();
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_BACKGROUND", background.as_str()),
        ("CONTRASTXR_CAPTURE_DIR", dir_text.as_str()),
        ("CONTRASTXR_CAPTURE_SKIP", "3"),
        ("CONTRASTXR_CAPTURE_FRAMES", "2"),
    ];
    let Some(run) = client_egl(&env, &[]) else {
        return;
    };
    let lines = layer_lines(&run);
    let what = format!("{lines:#?}");
    let api = "graphics API of this session: OpenGL (EGL), enhanced";
    assert!(lines.iter().any(|l| l.contains(api)), "{what}");
    assert!(!lines.iter().any(|l| l.contains("passing")), "{what}");
    let views = captures(&dir);
    assert_eq!(views.len(), 4, "2 frames x 2 views: {what}");
    for c in &views {
        assert_eq!(c.json["graphics"], "opengl");
        let changed = check_view(c);
        assert!(changed > 1000, "the method changed {changed} pixels");
    }
}

/// With the layer off the client's EGL images are read back exactly as written: the check the
/// pass-through case below rests on sees no change without the layer.
#[test]
fn without_the_layer_egl_images_are_untouched() {
    untouched(&[("CONTRASTXR", "0")]);
}

/// The app's EGL context cannot be made current for the layer (fault point
/// `gl-make-current`): its frames pass through with one line naming why (the layer tries again
/// ever less often), and every image is as the app wrote it.
#[test]
fn egl_context_not_current_passes_the_frames_through_with_one_line() {
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_FAULT", "gl-make-current"),
    ];
    let Some(run) = untouched(&env) else {
        return;
    };
    assert_one_retry_line(&run, "could not be made current");
}

/// `--check-gl-state` on the EGL context (tests/opengl_state.rs does it for GLX; its items' current
/// drawables are EGL pbuffer surfaces here): with the layer enhancing, as without it, nothing
/// the app set before xrEndFrame has changed after it (Monado's EGL path does not trade the
/// draw and read surfaces as its GLX one trades drawables). A disturbed draw surface is seen at
/// every check, so the check can fail.
#[test]
fn the_app_finds_its_egl_gl_state_after_xr_end_frame_with_the_layer_on_as_off() {
    let on = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
    ];
    let off = [("CONTRASTXR", "0")];
    for (layer, env) in [(true, &on[..]), (false, &off[..])] {
        let Some(run) = client_egl(env, &["--check-gl-state"]) else {
            return;
        };
        let report = run.client_report();
        let what = format!("layer {layer}: {}", run.describe());
        assert!(report["gl_state_checked"].as_u64() >= Some(10), "{what}");
        assert_eq!(report["gl_state_changed"], serde_json::json!([]), "{what}");
        let enhanced = layer_lines(&run)
            .iter()
            .any(|l| l.contains("processing frames (2 views per frame)"));
        assert_eq!(enhanced, layer, "{what}");
    }
    let disturb = [
        "--check-gl-state",
        "--disturb-gl-state",
        "glXGetCurrentDrawable",
    ];
    let Some(run) = client_egl(&off, &disturb) else {
        return;
    };
    let report = run.client_report();
    let changed = report["gl_state_changed"].as_array().unwrap();
    let checked = report["gl_state_checked"].as_u64().unwrap();
    let draw = "eglGetCurrentSurface(EGL_DRAW)";
    assert_eq!(changed.len() as u64, checked, "{}", run.describe());
    assert!(changed.iter().all(|c| c["what"] == draw), "{changed:#?}");
}

/// A switch to the app's EGL context that fails (fault point `gl-make-current`, which counts
/// the switch as failed after making it) is undone: the thread gets back the surfaces and
/// context it had, so the app's check finds nothing changed around xrEndFrame.
#[test]
fn a_failed_egl_context_switch_is_undone() {
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_FAULT", "gl-make-current"),
    ];
    let Some(run) = client_egl(&env, &["--check-gl-state"]) else {
        return;
    };
    let report = run.client_report();
    let what = run.describe();
    assert!(report["gl_state_checked"].as_u64() >= Some(10), "{what}");
    assert_eq!(report["gl_state_changed"], serde_json::json!([]), "{what}");
    assert_one_retry_line(&run, "could not be made current");
}

/// `--egl-bind-es`: the client binds EGL_OPENGL_ES_API on its thread before each xrEndFrame
/// with its OpenGL context current (EGL's default API on a thread that never bound one; Monado
/// binds EGL_OPENGL_API on it before the first frame, hence each frame). eglGetCurrent* and a
/// releasing eglMakeCurrent act on the bound API's context, so the layer binds EGL_OPENGL_API
/// for its check and switch and the app's API again after: with the layer enhancing, as
/// without it, eglQueryAPI answers EGL_OPENGL_ES_API after every xrEndFrame and the app's GL
/// state and EGL current context and surfaces are as it set them. (Mesa keeps one current
/// context for all APIs, so here a layer that ignored the API would pass too: the unit tests
/// of src/layer/graphics/opengl/egl_context.rs hold the switch against an EGL that keeps one
/// per API.)
#[test]
fn the_app_finds_the_egl_api_it_bound_after_enhanced_frames() {
    let on = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
    ];
    let off = [("CONTRASTXR", "0")];
    for (layer, env) in [(true, &on[..]), (false, &off[..])] {
        let Some(run) = client_egl(env, &["--egl-bind-es", "--check-gl-state"]) else {
            return;
        };
        let report = run.client_report();
        let what = format!("layer {layer}: {}", run.describe());
        assert!(report["egl_api_checked"].as_u64() >= Some(10), "{what}");
        assert_eq!(report["egl_api_changed"], serde_json::json!([]), "{what}");
        assert_eq!(report["gl_state_changed"], serde_json::json!([]), "{what}");
        let lines = layer_lines(&run);
        let enhanced = lines
            .iter()
            .any(|l| l.contains("processing frames (2 views per frame)"));
        assert_eq!(enhanced, layer, "{what}");
        assert!(!lines.iter().any(|l| l.contains("passing")), "{what}");
    }
}
