//! The project's client with OpenGL sessions (`--graphics opengl`) in what its Vulkan path
//! scripts, through the layer, against the real Monado runtime in the sandbox with its X server
//! (`xr-sandbox run --x11`): both projection layouts and quad layers enhanced within the CPU
//! reference (tests/common/capture_check.rs), each view read at its own array layer and image
//! rect (GL's rects count rows from the bottom), and the call-semantics A/B of
//! tests/call_semantics.rs: with the layer off and on the scripted calls get the same answers,
//! and the layer enhances the frames the Vulkan cases expect; and swapchains made and destroyed
//! between frames (`--churn-formats`); and 100 session cycles that leak nothing.

mod common;

use common::capture_check::{
    assert_follows_the_video, captures, check_view, sample, video_dir, Captured,
};
use common::gl_client::{client_opengl, GL_VIEW};
use common::semantics::{self, assert_same_answers, enhanced_frames, Case};
use common::{layer_lines, sandbox, scratch_dir, session_memory, RUN_TIMEOUT_S, XR_CLIENT};
use std::path::Path;

/// Each view's size in these runs.
const VIEW: (u64, u64) = GL_VIEW;

fn background() -> String {
    format!("image:{}", sample("background-meadow.png"))
}

/// The layer's variables for an enhancing run (its programs waited for at the first frame, by
/// the sandbox's CONTRASTXR_PIPELINES=wait) with `frames` frames captured into `dir` after 3,
/// against `background`.
fn layer_env(dir: &Path, background: &str, frames: u32) -> Vec<(String, String)> {
    [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_BACKGROUND", background),
        ("CONTRASTXR_CAPTURE_DIR", &dir.to_string_lossy()),
        ("CONTRASTXR_CAPTURE_SKIP", "3"),
        ("CONTRASTXR_CAPTURE_FRAMES", &frames.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect()
}

fn as_refs(v: &[(String, String)]) -> Vec<(&str, &str)> {
    v.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
}

/// A capture's image rect as (x, y, width, height) and its array layer.
fn placement(c: &Captured) -> ((u64, u64, u64, u64), u64) {
    let r = &c.json["rect"];
    let n = |k: &str| r[k].as_u64().unwrap();
    let rect = (n("x"), n("y"), n("width"), n("height"));
    (rect, c.json["image_array_index"].as_u64().unwrap())
}

/// Runs the client with the layer on and `extra`; asserts it ran, the layer enhanced
/// `views_per_frame` views per frame in the app's GL context and said nothing of passing
/// through; returns the captures.
fn enhanced_run(
    tag: &str,
    env: &[(String, String)],
    extra: &[&str],
    views: usize,
) -> Option<Vec<Captured>> {
    let run = client_opengl("R8G8B8A8_SRGB", 12, &as_refs(env), extra, RUN_TIMEOUT_S)?;
    run.assert_success();
    let lines = layer_lines(&run);
    let processing = format!("processing frames ({views} views per frame)");
    assert!(
        lines.iter().any(|l| l.contains(&processing)),
        "{tag}: {lines:#?}"
    );
    assert!(
        !lines.iter().any(|l| l.contains("passing")),
        "{tag}: {lines:#?}"
    );
    let dir = env
        .iter()
        .find(|(k, _)| k == "CONTRASTXR_CAPTURE_DIR")
        .unwrap();
    Some(captures(Path::new(&dir.1)))
}

/// Both projection layouts: every view within the CPU reference and visibly changed, each
/// read at its own place (array: layers 0 and 1, the whole image; side by side: layer 0, the
/// left and right halves), and the two views' pixels differ (the pattern is shifted per view).
#[test]
fn opengl_layouts_are_enhanced_at_their_own_rects() {
    let (w, h) = VIEW;
    let layouts = [
        ("array", [((0, 0, w, h), 0), ((0, 0, w, h), 1)]),
        ("side-by-side", [((0, 0, w, h), 0), ((w, 0, w, h), 0)]),
    ];
    for (layout, places) in layouts {
        let dir = scratch_dir(&format!("opengl-client-{layout}"));
        let env = layer_env(&dir, &background(), 2);
        let extra = ["--layout", layout];
        let Some(views) = enhanced_run(layout, &env, &extra, 2) else {
            return;
        };
        assert_eq!(views.len(), 4, "{layout}: 2 frames x 2 views");
        for c in &views {
            assert_eq!(c.json["graphics"], "opengl", "{layout}");
            let changed = check_view(c);
            assert!(
                changed > 1000,
                "{layout}: the method changed {changed} pixels"
            );
            let view = c.json["view"].as_u64().unwrap() as usize;
            assert_eq!(placement(c), places[view], "{layout}: view {view}");
        }
        assert_ne!(
            views[0].display, views[1].display,
            "{layout}: both views read the same pixels"
        );
    }
}

/// The client's own check of its GL images (read back at their next acquire): with the layer
/// off, the side-by-side texture and the quad's are found exactly as written, so the checks
/// above rest on a client that fills and reads 2D textures right.
#[test]
fn without_the_layer_side_by_side_and_quad_images_are_untouched() {
    let env = [("CONTRASTXR", "0")];
    let extra = ["--layout", "side-by-side", "--quad", "--check-untouched"];
    let Some(run) = client_opengl("R8G8B8A8_SRGB", 12, &env, &extra, RUN_TIMEOUT_S) else {
        return;
    };
    run.assert_success();
    let report = run.client_report();
    // Two swapchains, each image checked from its second acquire on.
    let checked = report["frames_checked"].as_u64().unwrap_or(0);
    assert!(checked >= 16, "{checked} checked: {}", run.describe());
    assert_eq!(report["frames_modified"], serde_json::json!([]));
    assert_eq!(report["layout"], "side-by-side");
    assert_eq!(report["quad"], true);
}

/// Quad layers of an OpenGL session are enhanced with CONTRASTXR_QUAD_LAYERS=1 (as
/// tests/layer.rs `quad_layers_are_enhanced_when_configured` for Vulkan): the quad within the
/// CPU reference. Split into two strips (two quad layers on the top and bottom halves of one
/// image, rects counted from the bottom), each strip's view holds exactly the rows of the whole
/// quad's view that it shows: the layer reads a GL sub-rect at the rows the app meant.
#[test]
fn opengl_quad_layers_are_enhanced_when_configured() {
    let quad_env = |tag: &str| {
        let dir = scratch_dir(tag);
        let mut env = layer_env(&dir, "color:#e0d020", 1);
        env.push(("CONTRASTXR_QUAD_LAYERS".into(), "1".into()));
        env
    };
    let env = quad_env("opengl-client-quad");
    let Some(whole) = enhanced_run("quad", &env, &["--quad"], 3) else {
        return;
    };
    assert_eq!(whole.len(), 3, "two projection views and the quad");
    for c in &whole {
        assert!(check_view(c) > 100, "view {}", c.json["view"]);
    }
    let (qw, qh) = (VIEW.0 / 2, VIEW.1 / 2);
    let quad = &whole[2];
    assert_eq!(placement(quad), ((0, 0, qw, qh), 0));
    let env = quad_env("opengl-client-quad-strips");
    let extra = ["--quad", "--quad-strips", "2"];
    let Some(strips) = enhanced_run("quad strips", &env, &extra, 4) else {
        return;
    };
    assert_eq!(strips.len(), 4, "two projection views and two strips");
    let row_bytes = (qw * quad.json["bytes_per_pixel"].as_u64().unwrap()) as usize;
    let half = (qh / 2) as usize;
    // Strip 0 is the image's top half: GL rows qh/2..qh.
    for (k, strip) in strips[2..].iter().enumerate() {
        assert!(check_view(strip) > 100, "strip {k}");
        let y = if k == 0 { qh - qh / 2 } else { 0 };
        assert_eq!(placement(strip), ((0, y, qw, qh / 2), 0), "strip {k}");
        // Captures hold rows top first.
        let rows = &quad.display[k * half * row_bytes..(k + 1) * half * row_bytes];
        assert!(
            strip.display == rows,
            "strip {k} read other rows than the whole quad shows there"
        );
    }
}

/// `case` with OpenGL sessions, layer off and on, in the runtime's first GL format and in
/// GL_SRGB8_ALPHA8: the same answers, and the frames the Vulkan case expects enhanced, with the
/// layer working in the app's context (never passing through).
fn check_case(tag: &str, case: Case) {
    for format in [None, Some("R8G8B8A8_SRGB")] {
        let tag = format!("opengl-{tag}-{}", format.unwrap_or("default"));
        let Some(sandbox) = sandbox() else { return };
        let mut cmd = vec![
            XR_CLIENT,
            "--graphics",
            "opengl",
            "--json",
            "--size",
            "64x48",
            "--script",
            case.script,
        ];
        if let Some(format) = format {
            cmd.extend_from_slice(&["--format", format]);
        }
        let off = sandbox.run_x11(&cmd, &[("CONTRASTXR", "0")]);
        let dir = scratch_dir(&format!("semantics-{tag}"));
        let mut env = layer_env(&dir, "color:#e0d020", 1000);
        env.retain(|(k, _)| k != "CONTRASTXR_CAPTURE_SKIP");
        let on = sandbox.run_x11(&cmd, &as_refs(&env));
        let answers = assert_same_answers(&tag, case, &off, &on);
        assert_eq!(
            enhanced_frames(&dir),
            case.enhanced,
            "{tag}: frames the layer enhanced ({answers:?})\n{}",
            on.stderr
        );
        let lines = layer_lines(&on);
        let api = "graphics API of this session: OpenGL (Xlib), enhanced";
        assert!(lines.iter().any(|l| l.contains(api)), "{tag}: {lines:#?}");
        assert!(
            !lines.iter().any(|l| l.contains("passing")),
            "{tag}: {lines:#?}"
        );
    }
}

/// One test per case of tests/common/semantics.rs run with OpenGL (they run in parallel).
macro_rules! cases {
    ($($name:ident: $case:ident;)*) => {$(
        #[test]
        fn $name() {
            check_case(stringify!($name), semantics::$case);
        }
    )*};
}

cases! {
    plain_frames: PLAIN_FRAMES;
    pipelined_frames: PIPELINED_FRAMES;
    double_release: DOUBLE_RELEASE;
    destroy_with_a_held_image: DESTROY_WITH_A_HELD_IMAGE;
    release_across_a_discarded_frame: RELEASE_ACROSS_A_DISCARDED_FRAME;
    acquire_past_the_image_count: ACQUIRE_PAST_THE_IMAGE_COUNT;
    release_after_the_next_acquire: RELEASE_AFTER_THE_NEXT_ACQUIRE;
    end_without_release: END_WITHOUT_RELEASE;
}

/// `--churn-formats` with OpenGL: before every frame the client makes a swapchain of the next
/// format Monado offers OpenGL apps (colour and depth, 32x32 and 1920x1080, on the frame thread,
/// as the app's context allows) and destroys the oldest; the layer goes on enhancing every frame
/// and no call fails.
#[test]
fn opengl_swapchain_churn_keeps_enhancing() {
    let dir = scratch_dir("opengl-client-churn");
    let env = layer_env(&dir, "color:#e0d020", 2);
    let extra = ["--frames", "40", "--churn-formats"];
    let Some(run) = client_opengl("R8G8B8A8_SRGB", 12, &as_refs(&env), &extra, RUN_TIMEOUT_S)
    else {
        return;
    };
    run.assert_success();
    let report = run.client_report();
    let churned = report["swapchains_churned"].as_u64().unwrap_or(0);
    assert!(
        churned >= 30,
        "{churned} swapchains churned: {}",
        run.describe()
    );
    let lines = layer_lines(&run);
    assert!(
        lines
            .iter()
            .any(|l| l.contains("processing frames (2 views per frame)")),
        "{lines:#?}"
    );
    assert!(!lines.iter().any(|l| l.contains("passing")), "{lines:#?}");
    let views = captures(&dir);
    assert_eq!(views.len(), 4, "{}", run.describe());
    for c in &views {
        assert!(check_view(c) > 100);
    }
}

/// A live background in an OpenGL session: the source's thread writes each camera frame's
/// texels into the engine's mapped upload buffer (the layer says so once it has), the frame
/// call uploads them, and every captured view is within the CPU reference computed from the
/// background frame it was enhanced against, over several different frames.
#[test]
fn opengl_live_background_is_written_on_the_source_thread() {
    let tag = "opengl-client-video";
    let dir = scratch_dir(tag);
    let video = video_dir(tag, 6);
    let env = layer_env(&dir, &format!("video:{}", video.display()), 12);
    let Some(run) = client_opengl("R8G8B8A8_SRGB", 24, &as_refs(&env), &[], RUN_TIMEOUT_S) else {
        return;
    };
    run.assert_success();
    let source =
        "live frames' texels are written into a mapped pixel buffer on the camera's thread";
    assert!(
        run.stderr.contains(source),
        "no {source:?}: {}",
        run.describe()
    );
    let views = captures(&dir);
    for c in &views {
        assert_eq!(c.json["graphics"], "opengl");
    }
    assert_follows_the_video(&views);
}

/// Waits until a captured frame's JSON in `dir` names `mode` in its settings; false at the
/// timeout.
fn wait_for_mode(dir: &std::path::Path, mode: &str, timeout: std::time::Duration) -> bool {
    let end = std::time::Instant::now() + timeout;
    let mut read = std::collections::HashSet::new();
    while std::time::Instant::now() < end {
        let files = std::fs::read_dir(dir).into_iter().flatten().flatten();
        for path in files.map(|e| e.path()) {
            if path.extension().is_none_or(|x| x != "json") || read.contains(&path) {
                continue;
            }
            // A file still being written reads again on the next pass.
            let text = std::fs::read_to_string(&path).unwrap_or_default();
            let Ok(json) = serde_json::from_str::<serde_json::Value>(&text) else {
                continue;
            };
            if json["params"]["mode"] == mode {
                return true;
            }
            read.insert(path);
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    false
}

/// A setting that needs other programs, changed while the app runs (`contrastxr set mode
/// heatmap` through the config file), has them built off the app's threads too, with empty
/// caches:
/// frames pass through meanwhile (no frame call builds them) and the heatmap then reaches the
/// app's views.
#[test]
fn opengl_programs_for_a_changed_mode_are_built_off_the_apps_threads() {
    if sandbox().is_none() {
        return;
    }
    let dir = scratch_dir("opengl-mode-change");
    let config = dir.join("config.toml");
    std::fs::write(&config, "mode = \"enhance\"\n").unwrap();
    let capture = dir.join("capture");
    let cache = dir.join("cache");
    let mut env = layer_env(&capture, "color:#e0d020", 100_000);
    env.retain(|(k, _)| k != "CONTRASTXR_PIPELINES");
    for (k, v) in [
        ("CONTRASTXR_PIPELINES", "background".to_string()),
        ("CONTRASTXR_CONFIG", config.to_string_lossy().into_owned()),
        ("XDG_CACHE_HOME", cache.to_string_lossy().into_owned()),
        ("CONTRASTXR_LOG", "debug".into()),
    ] {
        env.push((k.into(), v));
    }
    let stop = dir.join("stop");
    let stop_arg = stop.to_string_lossy().into_owned();
    let extra = ["--stop-file", stop_arg.as_str()];
    let run = std::thread::scope(|s| {
        // At most 120 s at the runtime's 20 Hz; the run ends once a heatmap frame is captured.
        // On a loaded machine (CI beside two busy loops) each of the two builds, with empty
        // caches, took 11 s.
        let run =
            s.spawn(|| client_opengl("R8G8B8A8_SRGB", 2400, &as_refs(&env), &extra, RUN_TIMEOUT_S));
        let first = capture.join("frame-5-view-0.json");
        common::wait_for(&first, std::time::Duration::from_secs(120));
        let out = std::process::Command::new(common::CLI)
            .args(["set", "mode", "heatmap"])
            .env("CONTRASTXR_CONFIG", &config)
            .output()
            .unwrap();
        let heatmap = wait_for_mode(&capture, "heatmap", std::time::Duration::from_secs(150));
        std::fs::write(&stop, "").unwrap();
        assert!(out.status.success(), "{out:?}");
        eprintln!("a heatmap frame captured: {heatmap}");
        run.join().unwrap()
    });
    let Some(run) = run else { return };
    run.assert_success();
    let report = run.client_report();
    assert_eq!(report["stopped_by_file"], true, "{}", run.describe());
    let lines = layer_lines(&run);
    let builds = lines
        .iter()
        .filter(|l| l.contains("building them on a thread of the layer's own"))
        .count();
    assert_eq!(builds, 2, "enhance, then heatmap: {lines:#?}");
    assert!(
        !lines.iter().any(|l| l.contains("built in frame calls")),
        "{lines:#?}"
    );
    let heatmap = captures(&capture)
        .into_iter()
        .filter(|c| c.json["params"]["mode"] == "heatmap")
        .count();
    assert!(heatmap > 0, "no heatmap frame captured: {lines:#?}");
}

/// 100 OpenGL sessions in one process, each with its contexts' objects made and deleted by the
/// layer (programs, textures, buffers, fences) and its build and background threads: resident
/// memory and open files stay flat (tests/common/session_memory.rs), as in the Vulkan cycles of
/// tests/hardening.rs, with two malloc arenas for the same reason.
#[test]
fn opengl_session_cycles_leak_nothing() {
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("MALLOC_ARENA_MAX", "2"),
    ];
    let cycles = ["--sessions", "100"];
    let Some(run) = client_opengl("R8G8B8A8_SRGB", 2, &env, &cycles, 600) else {
        return;
    };
    run.assert_success();
    let report = run.client_report();
    assert_eq!(report["sessions_run"], 100, "{}", run.describe());
    let sessions = layer_lines(&run)
        .iter()
        .filter(|l| l.starts_with("session on the app's OpenGL"))
        .count();
    assert_eq!(sessions, 100, "the layer ran each time: {}", run.describe());
    session_memory::assert_flat(
        "opengl cycles",
        &session_memory::samples(&report, "sessions"),
    );
}
