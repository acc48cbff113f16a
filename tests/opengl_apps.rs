//! OpenGL apps through the layer, against the real Monado runtime in the sandbox with its X
//! server (`xr-sandbox run --x11`: Xorg's dummy driver, GLX on llvmpipe). The layer enhances
//! Vulkan sessions only: an OpenGL session runs as it does without the layer, its frames
//! untouched, and the layer says so in one line (and nothing about views it does not touch).

mod common;

use common::{layer_lines, sandbox, ApiDump, SandboxRun};

/// hello_xr with OpenGL for `seconds` (it exits when its stdin closes), through the layer when
/// `layer` is true, its OpenXR calls recorded by api_dump below it.
fn hello_xr_opengl(tag: &str, layer: bool, seconds: u32) -> Option<(SandboxRun, ApiDump)> {
    let sandbox = sandbox()?;
    let dump = ApiDump::new(tag);
    let mut env = dump.env();
    env.push(("XR_ENABLE_API_LAYERS", ApiDump::LAYER));
    if layer {
        env.extend([
            ("CONTRASTXR", "1"),
            ("CONTRASTXR_FORCE", "1"),
            ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ]);
    }
    let script = format!("sleep {seconds} | hello_xr -g OpenGL");
    let run = sandbox.run_x11_for(&["sh", "-c", &script], &env, 120);
    Some((run, dump))
}

#[test]
fn hello_xr_with_opengl_runs_through_the_layer_as_without_it() {
    let Some((bare, bare_dump)) = hello_xr_opengl("opengl-bare", false, 4) else {
        return;
    };
    let Some((on, on_dump)) = hello_xr_opengl("opengl-layer", true, 4) else {
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
    // 4 s at 20 Hz is 80; start-up and a busy machine take some.
    let frames = |d: &ApiDump| d.calls("xrEndFrame").len();
    let (bare_frames, on_frames) = (frames(&bare_dump), frames(&on_dump));
    eprintln!("xrEndFrame calls in 4 s: {bare_frames} without the layer, {on_frames} with it");
    assert!(
        (30..=100).contains(&bare_frames),
        "{bare_frames} without the layer"
    );
    assert!(
        (30..=100).contains(&on_frames),
        "{on_frames} with the layer"
    );
    let lines = layer_lines(&on);
    let passing: Vec<_> = lines.iter().filter(|l| l.contains("passing")).collect();
    assert_eq!(passing.len(), 1, "{lines:#?}");
    assert!(
        passing[0].contains("not a Vulkan session (OpenGL (Xlib))"),
        "{lines:#?}"
    );
    // A session passed through has no views to register.
    assert!(
        !lines.iter().any(|l| l.contains("camera mapping")),
        "{lines:#?}"
    );
    assert!(layer_lines(&bare).is_empty(), "{:#?}", layer_lines(&bare));
}

/// The project's client with an OpenGL session (`--graphics opengl`: the Xlib binding on a GLX
/// 4.5 core context) in `format`, its images read back at each next acquire.
fn client_opengl(format: &str, layer: bool) -> Option<SandboxRun> {
    let sandbox = sandbox()?;
    let on = if layer { "1" } else { "0" };
    let env = [
        ("CONTRASTXR", on),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
    ];
    let cmd = [
        common::XR_CLIENT,
        "--graphics",
        "opengl",
        "--json",
        "--frames",
        "20",
        "--size",
        "64x48",
        "--check-untouched",
        "--format",
        format,
    ];
    Some(sandbox.run_x11_for(&cmd, &env, 120))
}

/// Every colour format Monado offers OpenGL apps, through the client: the session runs to its
/// end with the layer on as off, every image read back as the app wrote it, and the layer says
/// in one line that it passes the session through.
#[test]
fn the_client_with_opengl_runs_through_the_layer_in_every_format() {
    let formats = [
        ("R16G16B16A16_UNORM", "GL_RGBA16"),
        ("R16G16B16A16_SFLOAT", "GL_RGBA16F"),
        ("R8G8B8A8_SRGB", "GL_SRGB8_ALPHA8"),
        ("R8G8B8A8_UNORM", "GL_RGBA8"),
    ];
    for (format, gl_name) in formats {
        for layer in [false, true] {
            let Some(run) = client_opengl(format, layer) else {
                return;
            };
            run.assert_success();
            let report = run.client_report();
            let what = format!("{gl_name}, layer {layer}: {}", run.describe());
            assert_eq!(report["graphics"], "opengl", "{what}");
            assert_eq!(report["format"], gl_name, "{what}");
            assert!(report["frames_checked"].as_u64() >= Some(10), "{what}");
            assert_eq!(report["frames_modified"], serde_json::json!([]), "{what}");
            let lines = layer_lines(&run);
            if layer {
                let passing: Vec<_> = lines.iter().filter(|l| l.contains("passing")).collect();
                assert_eq!(passing.len(), 1, "{what}");
                assert!(passing[0].contains("OpenGL (Xlib)"), "{what}");
            } else {
                assert!(!lines.iter().any(|l| l.contains("passing")), "{what}");
            }
        }
    }
}
