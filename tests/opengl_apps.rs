//! OpenGL apps through the layer, against the real Monado runtime in the sandbox with its X
//! server (`xr-sandbox run --x11`: Xorg's dummy driver, GLX on llvmpipe). The layer enhances
//! their views in the app's own GL context: the captures of every colour format Monado offers
//! OpenGL apps are checked against the CPU reference (tests/common/capture_check.rs) with a
//! background that differs top to bottom, so a view read with GL's bottom-left origin taken
//! for a top-left one fails.

mod common;

use common::capture_check::{capture_dir, captures, check_view, sample};
use common::pass_through::{assert_one_pass_through_line, assert_one_retry_line, assert_untouched};
use common::{gl_client, layer_lines, sandbox, ApiDump, SandboxRun, RUN_TIMEOUT_S};
use std::path::Path;

/// The layer's variables for an enhancing run with two frames captured into `dir` (no
/// indicator: the captures are compared with the CPU reference).
fn layer_env(dir: &Path, mode: &str) -> Vec<(String, String)> {
    [
        ("CONTRASTXR", "1".to_string()),
        ("CONTRASTXR_FORCE", "1".into()),
        ("CONTRASTXR_INDICATOR", "0".into()),
        // Every frame enhanced, the first one waiting for the programs (an empty cache).
        ("CONTRASTXR_PIPELINES", "wait".into()),
        ("CONTRASTXR_MODE", mode.into()),
        (
            "CONTRASTXR_BACKGROUND",
            format!("image:{}", sample("background-meadow.png")),
        ),
        ("CONTRASTXR_CAPTURE_DIR", dir.to_string_lossy().into_owned()),
        ("CONTRASTXR_CAPTURE_SKIP", "3".into()),
        ("CONTRASTXR_CAPTURE_FRAMES", "2".into()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

fn as_refs(v: &[(String, String)]) -> Vec<(&str, &str)> {
    v.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
}

/// hello_xr with OpenGL for as long as the shell command `stdin` runs (it exits when its stdin
/// closes), through the layer with `env`, its OpenXR calls recorded by api_dump below it.
fn hello_xr_opengl(tag: &str, env: &[(&str, &str)], stdin: &str) -> Option<(SandboxRun, ApiDump)> {
    let sandbox = sandbox()?;
    let dump = ApiDump::new(tag);
    let mut all = dump.env();
    all.push(("XR_ENABLE_API_LAYERS", ApiDump::LAYER));
    all.extend_from_slice(env);
    let script = format!("{stdin} | hello_xr -g OpenGL");
    let run = sandbox.run_x11(&["sh", "-c", &script], &all);
    Some((run, dump))
}

#[test]
fn hello_xr_with_opengl_is_enhanced() {
    let Some((bare, bare_dump)) = hello_xr_opengl("opengl-bare", &[], "sleep 5") else {
        return;
    };
    // The programs built into the caches first, by a run that lasts until its captures exist:
    // with empty caches (a fresh machine's) the first frame waits for them, seconds on a loaded
    // machine, which the timed run below is not about (docs/performance.md measures it).
    let warm = capture_dir("opengl-hello-xr-warm");
    let warm_env = layer_env(&warm, "enhance");
    let until = common::stdin_until_captured(&warm, 4, 2);
    let Some((warmed, _)) = hello_xr_opengl("opengl-warm", &as_refs(&warm_env), &until) else {
        return;
    };
    warmed.assert_success();
    let dir = capture_dir("opengl-hello-xr");
    let env = layer_env(&dir, "enhance");
    let Some((on, on_dump)) = hello_xr_opengl("opengl-layer", &as_refs(&env), "sleep 5") else {
        return;
    };
    for (run, name) in [(&bare, "without the layer"), (&on, "with the layer")] {
        run.assert_success();
        let output = format!("{}{}", run.stdout, run.stderr);
        assert!(
            output.contains("XR_SESSION_STATE_FOCUSED"),
            "{name}: {}",
            run.describe()
        );
    }
    // 5 s at 20 Hz is 100; start-up and a busy machine take some. The caches are warm (above):
    // an empty one's cost is measured in docs/performance.md, not held here.
    let frames = |d: &ApiDump| d.calls("xrEndFrame").len();
    let (bare_frames, on_frames) = (frames(&bare_dump), frames(&on_dump));
    eprintln!("xrEndFrame calls in 5 s: {bare_frames} without the layer, {on_frames} with it");
    assert!((40..=120).contains(&bare_frames), "{bare_frames} without");
    assert!((10..=120).contains(&on_frames), "{on_frames} with");
    let lines = layer_lines(&on);
    let api = "graphics API of this session: OpenGL (Xlib), enhanced";
    assert!(lines.iter().any(|l| l.contains(api)), "{lines:#?}");
    assert!(!lines.iter().any(|l| l.contains("passing")), "{lines:#?}");
    let views = captures(&dir);
    assert_eq!(views.len(), 4, "2 frames x 2 views in {}", dir.display());
    for c in &views {
        assert_eq!(c.json["graphics"], "opengl");
        let changed = check_view(c);
        assert!(changed > 1000, "the method changed only {changed} pixels");
    }
    assert!(layer_lines(&bare).is_empty(), "{:#?}", layer_lines(&bare));
}

/// The project's client with an OpenGL session (one array swapchain) of 12 frames in
/// `format`, through the layer with `env`.
fn client_opengl(format: &str, env: &[(&str, &str)], extra: &[&str]) -> Option<SandboxRun> {
    gl_client::client_opengl(format, 12, env, extra, RUN_TIMEOUT_S)
}

/// The colour formats Monado offers OpenGL apps (no GL_RGB10_A2), by the client's names.
const FORMATS: [(&str, &str); 4] = [
    ("R16G16B16A16_UNORM", "GL_RGBA16"),
    ("R16G16B16A16_SFLOAT", "GL_RGBA16F"),
    ("R8G8B8A8_SRGB", "GL_SRGB8_ALPHA8"),
    ("R8G8B8A8_UNORM", "GL_RGBA8"),
];

/// Every colour format Monado offers OpenGL apps, through the client: both views of the
/// captured frames within the tolerance of the CPU reference, the method visibly at work, with
/// `in_place` at its default (on llvmpipe: through a buffer) and `on` (the formats with a
/// format stored in place through an image unit, an sRGB texture through a GL_RGBA8 view of the
/// runtime's immutable texture), as the capture JSON's `path` says.
#[test]
fn the_client_with_opengl_is_enhanced_in_every_format() {
    for in_place in ["auto", "on"] {
        for (format, gl_name) in FORMATS {
            let dir = capture_dir(&format!("opengl-{gl_name}-{in_place}"));
            let mut env = layer_env(&dir, "enhance");
            env.push(("CONTRASTXR_IN_PLACE".into(), in_place.into()));
            let Some(run) = client_opengl(format, &as_refs(&env), &[]) else {
                return;
            };
            run.assert_success();
            let what = format!("{gl_name}, in_place {in_place}: {}", run.describe());
            assert_eq!(run.client_report()["format"], gl_name, "{what}");
            let views = captures(&dir);
            assert_eq!(views.len(), 4, "{what}");
            for c in &views {
                assert_eq!(c.json["graphics"], "opengl", "{what}");
                assert_eq!(c.json["format"], gl_name, "{what}");
                if in_place == "on" {
                    assert_eq!(c.json["path"], "in-place", "{what}");
                }
                let changed = check_view(c);
                assert!(
                    changed > 1000,
                    "{gl_name}, in_place {in_place}: the method changed {changed} pixels"
                );
            }
            assert_ne!(
                views[0].json["image_array_index"], views[1].json["image_array_index"],
                "{what}"
            );
        }
    }
}

/// The other modes reach OpenGL sessions too: each changes the app's views, and mode off
/// leaves every image as the app wrote it (read back by the client at its next acquire).
#[test]
fn opengl_sessions_follow_every_mode() {
    for mode in ["background", "heatmap", "split"] {
        let dir = capture_dir(&format!("opengl-mode-{mode}"));
        let env = layer_env(&dir, mode);
        let Some(run) = client_opengl("R8G8B8A8_SRGB", &as_refs(&env), &[]) else {
            return;
        };
        run.assert_success();
        let views = captures(&dir);
        assert_eq!(views.len(), 4, "{mode}: {}", run.describe());
        for c in &views {
            assert_eq!(c.json["params"]["mode"], mode);
            assert_ne!(c.display, c.output, "{mode}: the view is unchanged");
        }
    }
    let dir = capture_dir("opengl-mode-off");
    let env = layer_env(&dir, "off");
    untouched(&as_refs(&env));
}

/// The client with `env`, its images read back at each next acquire: every one as the app
/// wrote it. Returns the run (None without the sandbox).
fn untouched(env: &[(&str, &str)]) -> Option<SandboxRun> {
    let run = client_opengl("R8G8B8A8_SRGB", env, &["--check-untouched"])?;
    run.assert_success();
    assert_untouched(&run);
    Some(run)
}

/// With the layer off the client's images are read back exactly as written: the check that
/// makes the enhanced runs above meaningful sees no change without the layer.
#[test]
fn without_the_layer_opengl_images_are_untouched() {
    untouched(&[("CONTRASTXR", "0")]);
}

/// What the layer cannot do in an app's GL context (a context older than 4.3, a lost context,
/// a program the driver refuses): the session passes through, every image exactly as the app
/// wrote it, with one line naming why. A context current on another thread may be free at a
/// later frame: its frames pass through, every image as written, with one line naming why and
/// saying the layer tries again.
#[test]
fn opengl_failures_pass_the_session_through_with_one_line() {
    let for_good = true;
    let cases = [
        ("gl-make-current", "could not be made current", !for_good),
        ("gl-old-context", "older than 4.3", for_good),
        ("gl-context-lost", "context was lost", for_good),
        ("gl-program-link", "did not build", for_good),
    ];
    for (point, why, session_passes) in cases {
        // An empty cache: a program loaded from its cached binary is never linked.
        let cache = capture_dir(&format!("opengl-fault-{point}-cache"));
        let cache = cache.to_string_lossy().into_owned();
        let env = [
            ("CONTRASTXR", "1"),
            ("CONTRASTXR_FORCE", "1"),
            ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
            ("CONTRASTXR_FAULT", point),
            ("XDG_CACHE_HOME", cache.as_str()),
        ];
        let Some(run) = untouched(&env) else {
            return;
        };
        match session_passes {
            true => assert_one_pass_through_line(&run, why),
            false => assert_one_retry_line(&run, why),
        }
    }
}

/// The layer on but not forced, on the simulated HMD, which offers only OPAQUE: the session is
/// never enhanced, so the layer never enters the app's context, not even to build its programs
/// at swapchain creation (which it does for a session it may act on); the images are untouched
/// and the log says why frames pass.
#[test]
fn an_opaque_session_gets_no_programs_built() {
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_LOG", "debug"),
    ];
    let Some(run) = untouched(&env) else {
        return;
    };
    let lines = layer_lines(&run);
    let what = run.describe();
    assert!(
        lines
            .iter()
            .any(|l| l.contains("is not ADDITIVE: passing frames through")),
        "{what}"
    );
    for never in [
        "the app's OpenGL context:",
        "OpenGL programs",
        "processing frames",
    ] {
        assert!(
            !lines.iter().any(|l| l.contains(never)),
            "{never:?}: {what}"
        );
    }
}

/// With empty caches the programs are built on a thread of the layer's own, in an OpenGL
/// context of its own, while the frames pass through, then linked from the caches in the app's
/// context; where that thread cannot start they are built in the app's context. Either way the
/// views are enhanced within the tolerance of the CPU reference, and no process is started
/// from the app: the layer runs from a copy of its library with a `contrastxr` beside it that
/// would leave a mark if anything ran it (the layer once ran `contrastxr gl-programs` there).
#[test]
fn opengl_programs_are_built_off_the_apps_threads_or_in_its_context() {
    let cases = [
        (None, "built on a thread of the layer's own in"),
        (
            Some("gl-program-thread"),
            "OpenGL programs built in the app's context: the build thread could not start",
        ),
    ];
    for (fault, said) in cases {
        let tag = fault.unwrap_or("thread");
        let dir = capture_dir(&format!("opengl-built-{tag}"));
        let cache = capture_dir(&format!("opengl-built-{tag}-cache"));
        let cache = cache.to_string_lossy().into_owned();
        let library = capture_dir(&format!("opengl-built-{tag}-library"));
        // The library the sandbox would install (scripts/xr-sandbox: <target>/debug).
        let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(
            || Path::new(env!("CARGO_MANIFEST_DIR")).join("target"),
            std::path::PathBuf::from,
        );
        let built = target.join("debug/libcontrastxr.so");
        let Some(_) = sandbox() else {
            return;
        };
        std::fs::copy(&built, library.join("libcontrastxr.so")).unwrap();
        let mark = library.join("the-tool-ran");
        let tool = library.join("contrastxr");
        std::fs::write(
            &tool,
            format!("#!/bin/sh\ntouch '{}'\nexit 1\n", mark.display()),
        )
        .unwrap();
        std::fs::set_permissions(&tool, std::os::unix::fs::PermissionsExt::from_mode(0o755))
            .unwrap();
        let mut env = layer_env(&dir, "enhance");
        env.push(("XDG_CACHE_HOME".into(), cache));
        env.push(("CONTRASTXR_LOG".into(), "debug".into()));
        let lib = library
            .join("libcontrastxr.so")
            .to_string_lossy()
            .into_owned();
        env.push(("CONTRASTXR_LAYER_LIB".into(), lib));
        if let Some(point) = fault {
            env.push(("CONTRASTXR_FAULT".into(), point.into()));
        }
        let Some(run) = client_opengl("R8G8B8A8_UNORM", &as_refs(&env), &[]) else {
            return;
        };
        run.assert_success();
        let lines = layer_lines(&run);
        let what = format!("{tag}: {lines:#?}");
        assert!(lines.iter().any(|l| l.contains(said)), "{what}");
        assert!(
            !mark.exists(),
            "{tag}: the layer ran the tool beside its library"
        );
        let views = captures(&dir);
        assert_eq!(views.len(), 4, "{what}");
        for c in &views {
            assert!(check_view(c) > 1000, "{what}");
        }
    }
}

/// A build off the app's threads that ends without the programs (fault point
/// `gl-program-build`) stalls no frame call: it is said in one line, and the frame calls build
/// the programs one per call, frames going through untouched meanwhile; no frame call builds
/// and runs a whole set (what the layer once did, for up to a minute). The views are then
/// enhanced as ever.
#[test]
fn a_failed_build_leaves_the_programs_to_the_frame_calls_one_at_a_time() {
    let dir = capture_dir("opengl-build-fails");
    let cache = capture_dir("opengl-build-fails-cache");
    let mut env = layer_env(&dir, "enhance");
    env.retain(|(k, _)| k != "CONTRASTXR_PIPELINES");
    for (k, v) in [
        ("CONTRASTXR_PIPELINES", "background"),
        ("XDG_CACHE_HOME", &*cache.to_string_lossy()),
        ("CONTRASTXR_LOG", "debug"),
        ("CONTRASTXR_FAULT", "gl-program-build"),
    ] {
        env.push((k.into(), v.into()));
    }
    let Some(run) =
        gl_client::client_opengl("R8G8B8A8_UNORM", 60, &as_refs(&env), &[], RUN_TIMEOUT_S)
    else {
        return;
    };
    run.assert_success();
    let lines = layer_lines(&run);
    let what = format!("{lines:#?}");
    let said: Vec<_> = lines
        .iter()
        .filter(|l| l.contains("were not built off the app's threads (the build failed"))
        .collect();
    assert_eq!(said.len(), 1, "{what}");
    assert!(said[0].contains("one program per call"), "{what}");
    assert!(
        !lines.iter().any(|l| l.contains("run once in a frame call")),
        "a frame call built a whole set: {what}"
    );
    let views = captures(&dir);
    assert!(!views.is_empty(), "no frame was enhanced: {what}");
    for c in &views {
        assert!(check_view(c) > 1000, "{what}");
    }
}

/// An OpenGL app that exits while the layer's program build still runs in the driver (an empty
/// cache, frames not waiting for it, 4 frames): the exit waits for the build before the exit
/// handler the app registered last (`--exit-marker`), and so before any destructor the driver
/// registered during the build; it says so once, and the app exits 0.
#[test]
fn an_opengl_app_that_exits_during_the_build_waits_for_it_first() {
    let cache = capture_dir("opengl-exit-during-build-cache");
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "background"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("XDG_CACHE_HOME", &*cache.to_string_lossy()),
    ];
    let extra = ["--exit-marker"];
    let Some(run) = gl_client::client_opengl("R8G8B8A8_UNORM", 4, &env, &extra, RUN_TIMEOUT_S)
    else {
        return;
    };
    run.assert_success();
    let lines = layer_lines(&run);
    let building = "built on a thread of the layer's own";
    assert!(!lines.iter().any(|l| l.contains(building)), "{lines:#?}");
    let waited: Vec<_> = lines.iter().filter(|l| l.contains("exit waited")).collect();
    assert_eq!(waited.len(), 1, "{lines:#?}");
    common::assert_exit_waits_first("opengl", &run.stderr);
}
