//! The camera behind a real app on the real Monado runtime (see tests/common/mod.rs for the
//! skip/require rule), with the V4L2 stand-in (tests/fake-v4l2) slow to open: once the app stops
//! being enhanced (its config switches `mode` to off mid-run) the camera closes, also when it
//! finishes opening only after that; and no frame-loop call of the app waits for the camera.

mod common;

use common::{layer_lines, sandbox, scratch_dir, CLI, XR_CLIENT};
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// "open MS" / "close MS" lines the stand-in appended.
fn events(log: &Path) -> Vec<(String, u128)> {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    text.lines()
        .filter_map(|l| {
            let (what, ms) = l.split_once(' ')?;
            Some((what.to_string(), ms.parse().ok()?))
        })
        .collect()
}

fn now_ms() -> u128 {
    let t = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH);
    t.unwrap().as_millis()
}

#[test]
fn a_slow_camera_closes_after_enhancing_stops_and_no_call_waits_for_it() {
    let Some(sandbox) = sandbox() else {
        return;
    };
    let dir = scratch_dir("camera-idle");
    let lib = common::fake_v4l2(&dir);
    let node = dir.join("video7");
    std::fs::write(&node, b"").unwrap();
    let log = dir.join("events");
    let config = dir.join("config.toml");
    std::fs::write(&config, "mode = \"enhance\"\n").unwrap();
    let (lib_s, node_s, log_s, config_s) = (
        lib.display().to_string(),
        node.display().to_string(),
        log.display().to_string(),
        config.display().to_string(),
    );
    let background = format!("v4l2:{node_s}");
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "background"),
        ("CONTRASTXR_CONFIG", config_s.as_str()),
        ("CONTRASTXR_BACKGROUND", background.as_str()),
    ];
    // The sandbox passes only the runtime's and the layer's variables: the stand-in's go on
    // the app's command line. 12 s at the null compositor's 20 Hz.
    let (preload, device, log_to) = (
        format!("LD_PRELOAD={lib_s}"),
        format!("FAKE_V4L2_DEVICE={node_s}"),
        format!("FAKE_V4L2_LOG={log_s}"),
    );
    let cmd = [
        "/usr/bin/env",
        &preload,
        &device,
        &log_to,
        "FAKE_V4L2_OPEN_DELAY_MS=3000",
        XR_CLIENT,
        "--json",
        "--timing",
        "--size",
        "64x48",
        "--frames",
        "240",
    ];
    let (run, switched) = std::thread::scope(|s| {
        let app = s.spawn(|| sandbox.run(&cmd, &env));
        // Enhancing stops while the camera is still opening (it takes 3 s to open).
        let deadline = Instant::now() + Duration::from_secs(120);
        while !std::fs::read_to_string(&log).is_ok_and(|t| t.contains("opening")) {
            if app.is_finished() || Instant::now() > deadline {
                let run = app.join().unwrap();
                let said: Vec<_> = layer_lines(&run)
                    .into_iter()
                    .filter(|l| !l.starts_with("setting"))
                    .collect();
                panic!("the camera was never opened: {said:#?}");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_millis(200));
        let switched = now_ms();
        let o = Command::new(CLI)
            .args(["set", "mode", "off"])
            .env("CONTRASTXR_CONFIG", &config)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (app.join().unwrap(), switched)
    });
    run.assert_success();
    let report = run.client_report();
    let lines = layer_lines(&run);
    let events = events(&log);
    println!("stand-in events (ms after the switch to off): {:?}", {
        let e: Vec<_> = events
            .iter()
            .map(|(w, t)| (w, *t as i128 - switched as i128))
            .collect();
        e
    });
    let opens = events.iter().filter(|(w, _)| w == "open").count();
    let closes: Vec<u128> = events
        .iter()
        .filter(|(w, _)| w == "close")
        .map(|(_, t)| *t)
        .collect();
    assert!(opens >= 1, "{events:?}");
    let opened = events.iter().find(|(w, _)| w == "open").unwrap().1;
    assert!(
        opened > switched,
        "the open ended before the switch: {events:?}"
    );
    assert_eq!(
        closes.len(),
        opens,
        "a camera left open: {events:?}\n{lines:#?}"
    );
    let last = *closes.iter().max().unwrap();
    assert!(
        last > switched && last - switched < 8000,
        "closed {} ms after the switch: {events:?}",
        last as i128 - switched as i128
    );
    let calls = report["timing"]["calls"]
        .as_object()
        .unwrap_or_else(|| panic!("no timing calls: {report}"));
    // xrWaitFrame is the runtime's frame pacing (50 ms at 20 Hz), which the layer does not see.
    for (name, t) in calls.iter().filter(|(n, _)| *n != "xrWaitFrame") {
        let max = t["max_ms"].as_f64().unwrap();
        println!("{name}: max {max:.1} ms");
        assert!(max < 100.0, "{name} took {max} ms: {report}");
    }
}

/// A run of the client (`--size 64x48 --frames 20`, then `extra`) through the layer with the
/// V4L2 stand-in as its camera, in a scratch folder `tag`: the run, and the stand-in's
/// "open"/"close" events.
struct StandInRun {
    out: common::SandboxRun,
    events: Vec<(String, u128)>,
}

fn run_with_stand_in(
    sandbox: &common::Sandbox,
    tag: &str,
    extra: &[&str],
    runs: usize,
) -> Vec<StandInRun> {
    let dir = scratch_dir(tag);
    let lib = common::fake_v4l2(&dir);
    let node = dir.join("video7");
    std::fs::write(&node, b"").unwrap();
    let log = dir.join("events");
    let background = format!("v4l2:{}", node.display());
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_BACKGROUND", background.as_str()),
    ];
    let (preload, device, log_to) = (
        format!("LD_PRELOAD={}", lib.display()),
        format!("FAKE_V4L2_DEVICE={}", node.display()),
        format!("FAKE_V4L2_LOG={}", log.display()),
    );
    let mut cmd = vec![
        "/usr/bin/env",
        &preload,
        &device,
        &log_to,
        XR_CLIENT,
        "--json",
        "--size",
        "64x48",
        "--frames",
        "20",
    ];
    cmd.extend(extra);
    (0..runs)
        .map(|_| {
            let _ = std::fs::remove_file(&log);
            let out = sandbox.run(&cmd, &env);
            StandInRun {
                out,
                events: events(&log),
            }
        })
        .collect()
}

/// An app that exits right after xrDestroySession (the client's next calls are
/// xrDestroyInstance and its exit): the session's end waits, boundedly, for the capture thread,
/// which restores the camera's controls and closes it, so the stand-in sees the close every
/// time (5 of 5 runs).
#[test]
fn the_camera_is_closed_when_the_session_ends() {
    let Some(sandbox) = sandbox() else {
        return;
    };
    let runs = run_with_stand_in(&sandbox, "camera-closed-at-end", &[], 5);
    for (run, r) in runs.iter().enumerate() {
        r.out.assert_success();
        let events: Vec<&str> = r.events.iter().map(|(w, _)| w.as_str()).collect();
        assert_eq!(
            events,
            ["open", "close"],
            "run {run}: {:#?}",
            layer_lines(&r.out)
        );
    }
}

/// An app that stops ending frames (paused, idle) for 5 s before it ends its session: the
/// camera's own thread closes it (controls restored, device closed) 2 s after the last frame
/// took one, long before xrDestroySession; and nothing is left open at the end.
#[test]
fn the_camera_closes_on_its_own_when_the_app_stops_ending_frames() {
    let Some(sandbox) = sandbox() else {
        return;
    };
    let tag = "camera-closed-when-paused";
    let r = run_with_stand_in(&sandbox, tag, &["--idle-ms", "5000"], 1).remove(0);
    let ended = now_ms();
    let (out, events) = (r.out, r.events);
    out.assert_success();
    let what: Vec<&str> = events.iter().map(|(w, _)| w.as_str()).collect();
    assert_eq!(what, ["open", "close"], "{:#?}", layer_lines(&out));
    // Closed about 2 s after the last frame, not at xrDestroySession (5 s after it).
    let closed = events[1].1;
    assert!(
        ended - closed > 2000,
        "closed {} ms before the app's end: {:#?}",
        ended - closed,
        layer_lines(&out)
    );
    let lines = layer_lines(&out);
    assert!(
        lines
            .iter()
            .any(|l| l.contains("the camera is closed until the next one")),
        "{lines:#?}"
    );
}
