//! The host's GL state is the host's: around every xrEndFrame of an OpenGL session the client
//! (`--check-gl-state`) sets non-default values of the GL state a layer working in the app's
//! context could touch and leaves a GL error pending, then reads it all back after the call.
//! With the layer on, the app must find exactly what it finds without it; and the check must be
//! able to fail (`--disturb-gl-state`, a layer that forgets to restore).

mod common;

use common::{sandbox, SandboxRun};
use serde_json::Value;

/// The client with an OpenGL session in `format`, its GL state checked around every
/// xrEndFrame, through the layer (on and enhancing whatever it can) when `layer` is true;
/// `disturb`: the items it changes on purpose before xrEndFrame.
fn client(format: &str, layer: bool, disturb: Option<&str>) -> Option<SandboxRun> {
    client_with(format, layer, disturb, &[])
}

/// `client` with `extra` added to the layer's environment.
fn client_with(
    format: &str,
    layer: bool,
    disturb: Option<&str>,
    extra: &[(&str, &str)],
) -> Option<SandboxRun> {
    let sandbox = sandbox()?;
    let on = if layer { "1" } else { "0" };
    let mut env = vec![
        ("CONTRASTXR", on),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        // Every frame enhanced, the first one included (it waits for the programs).
        ("CONTRASTXR_PIPELINES", "wait"),
    ];
    env.extend(extra);
    let mut cmd = vec![
        common::XR_CLIENT,
        "--graphics",
        "opengl",
        "--check-gl-state",
        "--json",
        "--frames",
        "20",
        "--size",
        "64x48",
        "--format",
        format,
    ];
    if let Some(items) = disturb {
        cmd.extend(["--disturb-gl-state", items]);
    }
    Some(sandbox.run_x11(&cmd, &env))
}

/// Monado's OpenGL (Xlib) client compositor saves the app's current drawables swapped (the draw
/// drawable from glXGetCurrentReadDrawable, the read one from glXGetCurrentDrawable) before it
/// makes the app's context current on the session's drawable, and restores them so: when the
/// app's draw and read drawables differ, they have traded places after xrEndFrame, with the
/// layer as without it (the client's check alternates: every second xrEndFrame it reads where
/// it draws, and there nothing at all may change). This names that change, and only that one:
/// both drawables in one frame, each one's value after being the other's before.
fn is_monados_drawable_swap(change: &Value, all: &[Value]) -> bool {
    let other = match change["what"].as_str() {
        Some("glXGetCurrentDrawable") => "glXGetCurrentReadDrawable",
        Some("glXGetCurrentReadDrawable") => "glXGetCurrentDrawable",
        _ => return false,
    };
    all.iter().any(|c| {
        c["frame"] == change["frame"]
            && c["what"] == other
            && c["before"] == change["after"]
            && c["after"] == change["before"]
    })
}

/// The run's report, the changes it found but Monado's drawable swap, and the frames with the
/// swap.
fn changes(run: &SandboxRun) -> (Value, Vec<Value>, Vec<u64>) {
    run.assert_success();
    let report = run.client_report();
    let all = report["gl_state_changed"]
        .as_array()
        .unwrap_or_else(|| panic!("no gl_state_changed: {}", run.describe()))
        .clone();
    let (swaps, others): (Vec<_>, Vec<_>) = all
        .iter()
        .cloned()
        .partition(|c| is_monados_drawable_swap(c, &all));
    let mut swap_frames: Vec<_> = swaps.iter().filter_map(|c| c["frame"].as_u64()).collect();
    swap_frames.dedup();
    (report, others, swap_frames)
}

#[test]
fn the_app_finds_its_gl_state_after_xr_end_frame_with_the_layer_on_as_off() {
    for format in ["R8G8B8A8_SRGB", "R16G16B16A16_SFLOAT"] {
        for layer in [false, true] {
            let Some(run) = client(format, layer, None) else {
                return;
            };
            let (report, others, swap_frames) = changes(&run);
            let what = format!("{format}, layer {layer}: {}", run.describe());
            let checked = report["gl_state_checked"].as_u64().unwrap_or(0);
            eprintln!(
                "{format}, layer {layer}: {checked} xrEndFrame calls checked, changed: {others:?}, \
                 Monado's drawable swap in {} of them",
                swap_frames.len()
            );
            assert!(checked >= 10, "{what}");
            let enhanced = common::layer_lines(&run)
                .iter()
                .any(|l| l.contains("processing frames (2 views per frame)"));
            assert_eq!(enhanced, layer, "{what}");
            assert_eq!(others, Vec::<Value>::new(), "{what}");
            // Monado's own change, seen without the layer: if it ever goes, the docs' note
            // about it (docs/testing.md) goes too.
            // Every second check the app reads where it draws: Monado's swap cannot show there.
            assert!(swap_frames.len() as u64 <= checked.div_ceil(2), "{what}");
            if !layer {
                assert!(
                    swap_frames.len() >= 5,
                    "Monado no longer swaps the app's draw and read drawables in xrEndFrame: \
                     is_monados_drawable_swap and docs/testing.md can go. {what}"
                );
            }
        }
    }
}

/// Every item --disturb-gl-state can change.
const DISTURBABLE: [&str; 10] = [
    "glXGetCurrentDrawable",
    "glGetError",
    "GL_ACTIVE_TEXTURE",
    "GL_CURRENT_PROGRAM",
    "GL_TEXTURE_BINDING_2D",
    "GL_IMAGE_BINDING_NAME",
    "GL_PIXEL_UNPACK_BUFFER_BINDING",
    "GL_UNPACK_ALIGNMENT",
    "GL_DRAW_FRAMEBUFFER_BINDING",
    "GL_FRAMEBUFFER_SRGB",
];

/// The check fails when something is not restored: one item disturbed is reported on every
/// frame checked, with its values, and nothing else is; each of the others is reported too.
#[test]
fn the_check_reports_gl_state_left_changed() {
    let Some(run) = client("R8G8B8A8_SRGB", true, Some("GL_ACTIVE_TEXTURE")) else {
        return;
    };
    let (report, others, _) = changes(&run);
    let what = run.describe();
    let checked = report["gl_state_checked"].as_u64().unwrap_or(0);
    assert!(checked >= 10, "{what}");
    assert_eq!(others.len() as u64, checked, "{others:#?}\n{what}");
    for change in &others {
        assert_eq!(change["what"], "GL_ACTIVE_TEXTURE", "{what}");
        // GL_TEXTURE5 set, GL_TEXTURE0 left.
        assert_eq!(change["before"], 0x84C5, "{what}");
        assert_eq!(change["after"], 0x84C0, "{what}");
    }

    let Some(run) = client("R8G8B8A8_SRGB", true, Some(&DISTURBABLE.join(","))) else {
        return;
    };
    let (_, others, _) = changes(&run);
    let what = run.describe();
    for item in DISTURBABLE {
        let seen = others.iter().any(|c| {
            let w = c["what"].as_str().unwrap_or("");
            w == item || w.starts_with(&format!("{item}["))
        });
        assert!(
            seen,
            "{item} disturbed but not reported: {others:#?}\n{what}"
        );
    }
    // The pending GL_INVALID_ENUM, read before xrEndFrame: it finds no error.
    let error = others.iter().find(|c| c["what"] == "glGetError").unwrap();
    assert_eq!(
        (&error["before"], &error["after"]),
        (&0x0500.into(), &0.into())
    );
}

/// The run with fault point `point` armed: the app's state checked at least 10 times and
/// found as it left it, and one line saying the session passes through, naming each of `says`.
/// A run before it fills a cache of its own, so that the programs are linked from it in the
/// app's context (no build thread meets the fault point first).
fn kept_and_passed_through(point: &str, says: &[&str]) {
    let Some((lines, what)) = kept_with_fault(point) else {
        return;
    };
    let passing: Vec<_> = lines.iter().filter(|l| l.contains("passing")).collect();
    assert_eq!(passing.len(), 1, "{what}");
    for said in says {
        assert!(passing[0].contains(said), "{said:?}: {what}");
    }
}

/// The client's GL state checked around every xrEndFrame of an enhanced session (programs
/// from a warm cache) with the fault point `point` armed: nothing changed for the app. The
/// layer's lines and the run's description (None without the sandbox).
fn kept_with_fault(point: &str) -> Option<(Vec<String>, String)> {
    let cache = common::scratch_dir(&format!("opengl-state-{point}-cache"));
    let cache = cache.to_string_lossy().into_owned();
    let warm = [("XDG_CACHE_HOME", cache.as_str())];
    client_with("R8G8B8A8_SRGB", true, None, &warm)?.assert_success();
    let fault = [
        ("XDG_CACHE_HOME", cache.as_str()),
        ("CONTRASTXR_FAULT", point),
    ];
    let run = client_with("R8G8B8A8_SRGB", true, None, &fault)?;
    let (report, others, _) = changes(&run);
    let what = format!("{point}: {}", run.describe());
    let checked = report["gl_state_checked"].as_u64().unwrap_or(0);
    assert!(checked >= 10, "{what}");
    assert_eq!(others, Vec::<Value>::new(), "{what}");
    Some((common::layer_lines(&run), what))
}

/// A panic inside the layer's OpenGL work, with its own framebuffer bound in the app's context
/// (fault point `gl-recipe-panic`), at xrCreateSwapchain (its first run, building the
/// programs) or in a frame call (`@1`): the app gets its swapchain, still finds its whole GL
/// state as it left it around every xrEndFrame (the saved state is put back as the panic
/// unwinds, and the context switch undone), and the session passes through from then on with
/// one line.
#[test]
fn a_panic_inside_the_recipe_leaves_the_apps_gl_state_as_it_was() {
    kept_and_passed_through(
        "gl-recipe-panic",
        &["internal error", "at xrCreateSwapchain"],
    );
    kept_and_passed_through("gl-recipe-panic@1", &["internal error", "while enhancing"]);
}

/// A context switch that fails (fault point `gl-make-current`: the layer makes the app's
/// context current on its own drawable, then counts the switch as failed) is undone: the
/// thread gets back the drawables and context it had, so the app's check finds nothing changed
/// around xrEndFrame. Such frames pass through with one line and the session keeps its engine:
/// a context current on another thread may be free again at a later frame.
#[test]
fn a_failed_context_switch_is_undone() {
    let Some((lines, what)) = kept_with_fault("gl-make-current") else {
        return;
    };
    let tries: Vec<_> = lines.iter().filter(|l| l.contains("tries again")).collect();
    assert_eq!(tries.len(), 1, "{what}");
    assert!(tries[0].contains("could not be made current"), "{what}");
    for never in ["passing", "processing frames", "enhancing again"] {
        assert!(
            !lines.iter().any(|l| l.contains(never)),
            "{never:?}: {what}"
        );
    }
}

/// A context that cannot be made current for a few calls only (`gl-make-current@10..12`, in
/// the frame calls) costs a few frames: they pass through, a later try succeeds, and the
/// session is enhanced again, with one line when the frames began to pass and one when
/// enhancement resumed, and the app's GL state kept throughout.
#[test]
fn a_context_free_again_is_enhanced_again() {
    let Some((lines, what)) = kept_with_fault("gl-make-current@10..12") else {
        return;
    };
    for (line, count) in [
        ("tries again", 1),
        ("enhancing again after", 1),
        ("passing", 0),
    ] {
        let seen = lines.iter().filter(|l| l.contains(line)).count();
        assert_eq!(seen, count, "{line:?}: {what}");
    }
    assert!(
        lines.iter().any(|l| l.contains("processing frames")),
        "{what}"
    );
}

/// The app's X errors are the app's: a thread of the client keeps making X errors on a second
/// X connection, counted by the client's own error handler, while every xrEndFrame is called
/// with the client's context released, so that the layer makes the app's context current and
/// puts it back around each frame (with its X error handler in place for its own switch).
/// Every error the client made reaches the client's handler, none swallowed by the layer's,
/// and the frames are enhanced.
#[test]
fn the_apps_x_errors_reach_its_handler_while_the_layer_switches_contexts() {
    let Some(sandbox) = sandbox() else {
        return;
    };
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_PIPELINES", "wait"),
    ];
    let cmd = [
        common::XR_CLIENT,
        "--graphics",
        "opengl",
        "--x-errors-elsewhere",
        "--json",
        "--frames",
        "150",
        "--size",
        "64x48",
        "--format",
        "R8G8B8A8_SRGB",
    ];
    let run = sandbox.run_x11(&cmd, &env);
    run.assert_success();
    let report = run.client_report();
    let what = run.describe();
    let made = report["x_errors_made"].as_u64().expect("x_errors_made");
    let seen = report["x_errors_seen"].as_u64().expect("x_errors_seen");
    eprintln!("X errors made {made}, seen by the app's handler {seen}");
    assert!(made >= 100, "too few errors made to tell: {what}");
    assert_eq!(seen, made, "the app's handler missed X errors: {what}");
    let enhanced = common::layer_lines(&run)
        .iter()
        .any(|l| l.contains("processing frames (2 views per frame)"));
    assert!(enhanced, "{what}");
}

/// The perceptual method binds one more shader storage buffer, its view's model: the app finds
/// that binding (and every other) as it left it, every frame enhanced.
#[test]
fn the_perceptual_methods_model_binding_is_put_back() {
    let extra = [("CONTRASTXR_METHOD", "perceptual")];
    let Some(run) = client_with("R8G8B8A8_SRGB", true, None, &extra) else {
        return;
    };
    let (report, others, _) = changes(&run);
    let what = run.describe();
    let checked = report["gl_state_checked"].as_u64().unwrap_or(0);
    assert!(checked >= 10, "{what}");
    let lines = common::layer_lines(&run);
    assert!(
        lines
            .iter()
            .any(|l| l.contains("processing frames (2 views per frame)")),
        "{what}"
    );
    assert_eq!(others, Vec::<Value>::new(), "{what}");
}
