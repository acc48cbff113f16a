//! The in-headset indicator, seen in the layer's captures (what the runtime gets) on the real
//! Monado runtime with core, Vulkan and synchronisation validation: the test client's frames
//! through the layer with the indicator on and with it off are the same except for the
//! indicator's text, which is there in the first frames, in its colour, where it belongs, and
//! gone once it expired; and it shows again, with the new value, after `contrastxr set`.

mod common;

use common::{sandbox, scratch_dir, wait_for, Validation, CLI, SYNC_VALIDATION, XR_CLIENT};
use std::path::{Path, PathBuf};
use std::time::Duration;

const WIDTH: usize = 320;
const HEIGHT: usize = 240;
const FRAMES: usize = 60;
/// The indicator's colour (sRGB, the swapchain below is R8G8B8A8_SRGB).
const GREEN: [u8; 4] = [64, 255, 64, 255];
/// "CONTRASTXR ENHANCE λE 0.40": 26 glyphs of 5x7 pixels, 1 blank column between them.
const TEXT_WIDTH: usize = 26 * 6 - 1;

/// Runs the client for FRAMES frames, capturing every frame; returns the capture folder.
fn run(tag: &str, extra: &[(&str, &str)]) -> Option<PathBuf> {
    let dir = scratch_dir(&format!("{tag}.capture"));
    run_into(tag, &dir, FRAMES, extra).then_some(dir)
}

/// The same with an OpenGL session (GLX, the sandbox's X server), its first frame waiting for
/// the layer's programs so that the indicator's first frames are captured.
fn run_opengl(tag: &str, extra: &[(&str, &str)]) -> Option<PathBuf> {
    let sandbox = sandbox()?;
    let dir = scratch_dir(&format!("{tag}.capture"));
    let (dir_s, frames) = (dir.to_string_lossy().into_owned(), FRAMES.to_string());
    let mut env = layer_env(&dir_s, &frames);
    env.push(("CONTRASTXR_PIPELINES", "wait"));
    env.extend_from_slice(extra);
    let cmd = client_cmd(&frames, true);
    let cmd: Vec<&str> = cmd.iter().map(String::as_str).collect();
    sandbox.run_x11(&cmd, &env).assert_success();
    Some(dir)
}

/// The client's command for `frames` frames: a Vulkan session with validation, or with
/// `opengl` an OpenGL one.
fn client_cmd(frames: &str, opengl: bool) -> Vec<String> {
    let size = format!("{WIDTH}x{HEIGHT}");
    let mut cmd: Vec<String> = [XR_CLIENT, "--json", "--frames", frames, "--size", &size]
        .into_iter()
        .chain(["--format", "R8G8B8A8_SRGB"])
        .map(String::from)
        .collect();
    match opengl {
        true => cmd.extend(["--graphics".into(), "opengl".into()]),
        false => cmd.push("--validation".into()),
    }
    cmd
}

/// The layer forced on against a flat background, every frame captured into `dir`.
fn layer_env<'a>(dir: &'a str, frames: &'a str) -> Vec<(&'a str, &'a str)> {
    vec![
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
        ("CONTRASTXR_CAPTURE_DIR", dir),
        ("CONTRASTXR_CAPTURE_FRAMES", frames),
    ]
}

/// Runs the client for `frames` frames, capturing every frame into `dir`; false without sandbox.
fn run_into(tag: &str, dir: &Path, frames: usize, extra: &[(&str, &str)]) -> bool {
    let Some(sandbox) = sandbox() else {
        return false;
    };
    let (dir_s, frames) = (dir.to_string_lossy().into_owned(), frames.to_string());
    let validation = Validation::new(tag);
    let mut env = validation.env();
    env.push(SYNC_VALIDATION);
    env.extend(layer_env(&dir_s, &frames));
    env.extend_from_slice(extra);
    let cmd = client_cmd(&frames, false);
    let cmd: Vec<&str> = cmd.iter().map(String::as_str).collect();
    sandbox.run(&cmd, &env).assert_success();
    validation.assert_clean();
    true
}

fn raw(dir: &Path, frame: usize, view: usize, kind: &str) -> Vec<[u8; 4]> {
    let path = dir.join(format!("frame-{frame}-view-{view}-{kind}.raw"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(bytes.len(), WIDTH * HEIGHT * 4, "{}", path.display());
    bytes
        .as_chunks::<4>()
        .0
        .iter()
        .map(|p| [p[0], p[1], p[2], p[3]])
        .collect()
}

/// Indicator pixels in a captured view, found without a reference run: the indicator's colour
/// where the app drew black (the enhancement leaves black exactly as it is).
fn indicator_pixels(dir: &Path, frame: usize, view: usize) -> usize {
    let (display, output) = (
        raw(dir, frame, view, "display"),
        raw(dir, frame, view, "output"),
    );
    display
        .iter()
        .zip(&output)
        .filter(|(d, o)| d[..3] == [0, 0, 0] && **o == GREEN)
        .count()
}

fn output(dir: &Path, frame: usize, view: usize) -> Vec<[u8; 4]> {
    raw(dir, frame, view, "output")
}

/// The pixels (x, y) where the two outputs differ.
fn differences(a: &[[u8; 4]], b: &[[u8; 4]]) -> Vec<(usize, usize)> {
    (0..a.len())
        .filter(|&i| a[i] != b[i])
        .map(|i| (i % WIDTH, i / WIDTH))
        .collect()
}

#[test]
fn indicator_shows_in_the_first_frames_then_expires_and_can_be_switched_off() {
    check_indicator("indicator", run);
}

/// The same in an OpenGL session: drawn in the app's context, rows counted from the top as
/// the view is seen (GL stores them from the bottom).
#[test]
fn the_indicator_shows_in_opengl_sessions_too() {
    check_indicator("indicator-opengl", run_opengl);
}

type Runner = fn(&str, &[(&str, &str)]) -> Option<PathBuf>;

fn check_indicator(tag: &str, run: Runner) {
    let seconds = [("CONTRASTXR_INDICATOR_SECONDS", "1")];
    let Some(on) = run(&format!("{tag}-on"), &seconds) else {
        return;
    };
    let off = run(
        &format!("{tag}-off"),
        &[seconds[0], ("CONTRASTXR_INDICATOR", "0")],
    )
    .expect("the sandbox ran once");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(on.join("frame-0-view-0.json")).unwrap())
            .unwrap();
    assert_eq!(json["params"]["indicator"], true, "{json}");
    for view in 0..2 {
        // First frame: the text, and nothing else, differs.
        let (a, b) = (output(&on, 0, view), output(&off, 0, view));
        let diff = differences(&a, &b);
        assert!(
            diff.len() > 300,
            "view {view}: {} pixels differ",
            diff.len()
        );
        for &(x, y) in &diff {
            assert_eq!(a[y * WIDTH + x], GREEN, "view {view} ({x}, {y})");
        }
        // Where it belongs: a line of 7 rows a fifth of the way down, centred, text-wide.
        let xs = diff.iter().map(|d| d.0);
        let ys = diff.iter().map(|d| d.1);
        let (x0, x1) = (xs.clone().min().unwrap(), xs.max().unwrap());
        let (y0, y1) = (ys.clone().min().unwrap(), ys.max().unwrap());
        assert_eq!((y0, y1), (HEIGHT / 5, HEIGHT / 5 + 6), "view {view}");
        let left = (WIDTH - TEXT_WIDTH) / 2;
        // 'C' lights its first column, '0' its last.
        assert_eq!((x0, x1), (left, left + TEXT_WIDTH - 1), "view {view}");
        // The indicator was drawn over the app's content (the off run has no green there).
        assert!(diff.iter().all(|&(x, y)| b[y * WIDTH + x] != GREEN));
        // Later: gone, for good (no settings changed).
        let gone = (0..FRAMES)
            .find(|&f| output(&on, f, view) == output(&off, f, view))
            .unwrap_or_else(|| panic!("view {view}: the indicator never expired"));
        for f in gone..FRAMES {
            assert_eq!(output(&on, f, view), output(&off, f, view), "frame {f}");
        }
        println!(
            "view {view}: {} indicator pixels, gone from frame {gone}",
            diff.len()
        );
    }
}

#[test]
fn indicator_shows_again_after_a_settings_change() {
    if sandbox().is_none() {
        return;
    }
    let dir = scratch_dir("indicator-change");
    let config = dir.join("config.toml");
    std::fs::write(&config, "indicator_seconds = 1.0\n").unwrap();
    let capture = dir.join("capture");
    let config_s = config.to_string_lossy().into_owned();
    let frames = 120; // 6 s at the null compositor's 20 Hz, longer with captures
    std::thread::scope(|s| {
        let app = s.spawn(|| {
            run_into(
                "indicator-change",
                &capture,
                frames,
                &[("CONTRASTXR_CONFIG", config_s.as_str())],
            )
        });
        assert!(wait_for(
            &capture.join("frame-5-view-0.json"),
            Duration::from_secs(60)
        ));
        // Well after the first indicator expired (1 s after the first frame).
        std::thread::sleep(Duration::from_millis(1500));
        let o = std::process::Command::new(CLI)
            .args(["set", "lambda_e", "0.6"])
            .env("CONTRASTXR_CONFIG", &config)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(app.join().unwrap());
    });
    let lambda = |f: usize| {
        let text = std::fs::read_to_string(capture.join(format!("frame-{f}-view-0.json")));
        let v: serde_json::Value = serde_json::from_str(&text.unwrap()).unwrap();
        v["params"]["lambda_e"].as_f64().unwrap()
    };
    let shown: Vec<usize> = (0..frames)
        .map(|f| indicator_pixels(&capture, f, 0))
        .collect();
    let first_new = (0..frames)
        .find(|&f| lambda(f) > 0.5)
        .expect("a frame at lambda_e 0.6");
    println!("indicator pixels on black per frame: {shown:?}; lambda_e 0.6 from frame {first_new}");
    assert!(shown[0] > 10, "not at start: {shown:?}");
    assert!(
        shown[..first_new].contains(&0),
        "it never expired before the change: {shown:?}"
    );
    assert!(
        shown[first_new] > 10,
        "not shown with the change: {shown:?}"
    );
    assert_eq!(shown[frames - 1], 0, "still shown at the end: {shown:?}");
}
