//! An app that runs with privileges its user lacks (here setgid to `nogroup`, which sets the
//! kernel's AT_SECURE for it, as setuid and file capabilities do): the layer, loaded and asked
//! to enhance, leaves it alone. It reads none of the environment that would make it write files
//! with the app's privileges (the log folder from `XDG_STATE_HOME` among them), changes no
//! frame, and says why in one line on stderr. Against the real Monado runtime in the sandbox.
//!
//! The OpenXR loader of an elevated process reads only the system's layer folders, so the
//! layer's manifest is moved to `/etc/xdg/openxr/1/api_layers/implicit.d` for these runs (the
//! sandbox's `--overlay`: the change ends with the run).

mod common;

use common::{layer_lines, sandbox, scratch_dir, SandboxRun, XR_CLIENT};
use std::os::unix::fs::PermissionsExt;
use std::path::Path;

/// `nogroup`: a group the tests' user (root) is not in, so that a copy runs setgid to it.
const NOGROUP: u32 = 65534;

/// Moves the sandbox's user layer manifest into the system's folder, then runs `client`.
const SYSTEM_LAYER: &str = "set -e; d=/etc/xdg/openxr/1/api_layers/implicit.d; mkdir -p $d; \
    mv \"$XDG_DATA_HOME\"/openxr/1/api_layers/implicit.d/contrastxr.json $d/; exec \"$@\"";

/// Runs `client` (20 frames, each checked untouched) with the layer asked to enhance them and
/// `state` as its XDG_STATE_HOME.
fn run(client: &Path, state: &Path) -> SandboxRun {
    let sandbox = sandbox().expect("checked by the caller");
    let state_env = format!("XDG_STATE_HOME={}", state.display());
    let env = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_BACKGROUND", "color:#e0d020"),
    ];
    // The sandbox passes only some variables in: XDG_STATE_HOME goes on the command line.
    let cmd = [
        "/bin/sh",
        "-c",
        SYSTEM_LAYER,
        "sh",
        "/usr/bin/env",
        &state_env,
        client.to_str().unwrap(),
        "--json",
        "--frames",
        "20",
        "--size",
        "64x48",
        "--check-untouched",
    ];
    let run = sandbox.run_overlay(&cmd, &env);
    run.assert_success();
    run
}

#[test]
fn elevated_apps_are_passed_through_without_their_environment() {
    if sandbox().is_none() {
        return;
    }
    let dir = scratch_dir("elevated");
    let client = dir.join("contrastxr-xr-client");
    std::fs::copy(XR_CLIENT, &client).expect("copy the client");
    // The same client unprivileged, the layer's manifest where an elevated app's loader finds
    // it: the layer enhances and logs to the app's XDG_STATE_HOME.
    let state = dir.join("state-plain");
    let plain = run(&client, &state);
    let modified = plain.client_report()["frames_modified"].clone();
    assert!(
        modified.as_array().is_some_and(|m| !m.is_empty()),
        "{}",
        plain.describe()
    );
    assert!(state.join("contrastxr/layer.log").is_file());
    // Setgid: passed through, one line, nothing written.
    std::os::unix::fs::chown(&client, None, Some(NOGROUP)).expect("chgrp nogroup");
    std::fs::set_permissions(&client, std::fs::Permissions::from_mode(0o2755)).unwrap();
    let state = dir.join("state-elevated");
    let elevated = run(&client, &state);
    let lines = layer_lines(&elevated);
    assert_eq!(lines.len(), 1, "{lines:#?}");
    assert!(lines[0].contains("privileges its user lacks"), "{lines:#?}");
    let report = elevated.client_report();
    assert!(report["frames_checked"].as_u64() >= Some(10), "{report}");
    assert_eq!(report["frames_modified"], serde_json::json!([]), "{report}");
    assert!(
        !state.join("contrastxr").exists(),
        "the layer wrote under the app's XDG_STATE_HOME"
    );
}
