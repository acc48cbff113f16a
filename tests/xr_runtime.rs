//! Whole-system tests against the real Monado runtime (null compositor, simulated HMD) in the
//! sandbox: hello_xr and the project's XR test client, with the OpenXR core validation layer and
//! the Vulkan validation layer on. What the apps did is checked independently of their own
//! output through the LunarG api_dump layer's record of their OpenXR calls.
//!
//! Needs `scripts/xr-sandbox setup` (root); see tests/common/mod.rs for the skip/require rule.

mod common;

use common::{sandbox, ApiDump, Validation, XR_CLIENT};

/// The client's per-view size in these tests: set explicitly so the swapchain sizes can be
/// checked without trusting the client.
const VIEW_W: i64 = 200;
const VIEW_H: i64 = 150;
const FRAMES: usize = 20;

/// VkFormat values, from the Vulkan specification.
fn vk_format(name: &str) -> i64 {
    match name {
        "R8G8B8A8_UNORM" => 37,
        "R8G8B8A8_SRGB" => 43,
        "B8G8R8A8_UNORM" => 44,
        "B8G8R8A8_SRGB" => 50,
        "A2B10G10R10_UNORM" => 64,
        "R16G16B16A16_UNORM" => 91,
        "R16G16B16A16_SFLOAT" => 97,
        _ => panic!("unknown format {name}"),
    }
}

/// Runs the client with both validation layers and api_dump; checks it ran clean.
fn run_client(tag: &str, args: &[&str]) -> Option<(serde_json::Value, ApiDump)> {
    let sandbox = sandbox()?;
    let validation = Validation::new(tag).with_xr_layer(ApiDump::LAYER);
    let dump = ApiDump::new(tag);
    let (frames, size) = (FRAMES.to_string(), format!("{VIEW_W}x{VIEW_H}"));
    let mut cmd = vec![
        XR_CLIENT,
        "--validation",
        "--json",
        "--frames",
        &frames,
        "--size",
        &size,
    ];
    cmd.extend(args);
    let env = [validation.env(), dump.env()].concat();
    let run = sandbox.run(&cmd, &env);
    run.assert_success();
    validation.assert_clean();
    let report = run.client_report();
    Some((report, dump))
}

/// The client with one format and layout: the swapchain it made, the frames it ended and how
/// its session ended, as the api_dump layer saw them.
fn client_renders(format: &str, layout: &str, quad: bool) {
    let tag = format!(
        "client-{format}-{layout}{}",
        if quad { "-quad" } else { "" }
    );
    let mut args = vec!["--format", format, "--layout", layout];
    if quad {
        args.push("--quad");
    }
    let Some((report, dump)) = run_client(&tag, &args) else {
        return;
    };
    assert_eq!(report["format"], format);
    assert_eq!(report["ok"], true);

    let swapchains = dump.calls("xrCreateSwapchain");
    assert_eq!(swapchains.len(), 1 + quad as usize, "swapchains created");
    let projection = &swapchains[0];
    let (width, array_size) = if layout == "array" {
        (VIEW_W, 2)
    } else {
        (2 * VIEW_W, 1)
    };
    assert_eq!(
        projection.int("createInfo->format"),
        Some(vk_format(format))
    );
    assert_eq!(projection.int("createInfo->width"), Some(width));
    assert_eq!(projection.int("createInfo->height"), Some(VIEW_H));
    assert_eq!(projection.int("createInfo->arraySize"), Some(array_size));

    let frames: Vec<_> = dump
        .calls("xrEndFrame")
        .into_iter()
        .filter(|c| c.int("frameEndInfo->layerCount") > Some(0))
        .collect();
    assert!(
        frames.len() >= FRAMES,
        "{} frames with layers, wanted {FRAMES}",
        frames.len()
    );
    let view1 = "frameEndInfo->layers[0]->views[1].subImage";
    for frame in &frames {
        assert_eq!(frame.int("frameEndInfo->layerCount"), Some(1 + quad as i64));
        let (index, x) = if layout == "array" {
            (1, 0)
        } else {
            (0, VIEW_W)
        };
        assert_eq!(frame.int(&format!("{view1}.imageArrayIndex")), Some(index));
        assert_eq!(frame.int(&format!("{view1}.imageRect.offset.x")), Some(x));
        assert_eq!(
            frame.int(&format!("{view1}.imageRect.extent.width")),
            Some(VIEW_W)
        );
        if quad {
            assert_eq!(
                frame.get("frameEndInfo->layers[1]->type"),
                Some("XR_TYPE_COMPOSITION_LAYER_QUAD")
            );
        }
    }
    assert_eq!(
        dump.calls("xrRequestExitSession").len(),
        1,
        "the client asks to exit once"
    );
    assert_eq!(
        dump.calls("xrEndSession").len(),
        1,
        "the session ends cleanly"
    );
}

macro_rules! client_tests {
    ($($name:ident: $format:literal, $layout:literal;)*) => {
        $(
            #[test]
            fn $name() {
                client_renders($format, $layout, false);
            }
        )*
    };
}

client_tests! {
    client_r8g8b8a8_srgb_array: "R8G8B8A8_SRGB", "array";
    client_r8g8b8a8_srgb_side_by_side: "R8G8B8A8_SRGB", "side-by-side";
    client_b8g8r8a8_srgb_array: "B8G8R8A8_SRGB", "array";
    client_b8g8r8a8_srgb_side_by_side: "B8G8R8A8_SRGB", "side-by-side";
    client_r8g8b8a8_unorm_array: "R8G8B8A8_UNORM", "array";
    client_r8g8b8a8_unorm_side_by_side: "R8G8B8A8_UNORM", "side-by-side";
    client_b8g8r8a8_unorm_array: "B8G8R8A8_UNORM", "array";
    client_b8g8r8a8_unorm_side_by_side: "B8G8R8A8_UNORM", "side-by-side";
    client_r16g16b16a16_unorm_array: "R16G16B16A16_UNORM", "array";
    client_r16g16b16a16_unorm_side_by_side: "R16G16B16A16_UNORM", "side-by-side";
    client_r16g16b16a16_sfloat_array: "R16G16B16A16_SFLOAT", "array";
    client_r16g16b16a16_sfloat_side_by_side: "R16G16B16A16_SFLOAT", "side-by-side";
}

#[test]
fn client_with_a_quad_layer() {
    client_renders("B8G8R8A8_SRGB", "array", true);
}

/// Monado 25 does not offer A2B10G10R10: the client must then refuse it with a clear message
/// (and render it where a runtime does offer it).
#[test]
fn client_a2b10g10r10_rendered_when_offered_and_refused_clearly_otherwise() {
    let Some(sandbox) = sandbox() else { return };
    let list = sandbox.run(&[XR_CLIENT, "--list-formats"], &[]);
    list.assert_success();
    if list.stdout.lines().any(|l| l == "A2B10G10R10_UNORM") {
        client_renders("A2B10G10R10_UNORM", "array", false);
        return;
    }
    let run = sandbox.run(
        &[XR_CLIENT, "--format", "A2B10G10R10_UNORM", "--frames", "2"],
        &[],
    );
    assert!(!run.success(), "the client must fail: {}", run.describe());
    assert!(
        run.stdout.contains("does not offer A2B10G10R10_UNORM"),
        "{}",
        run.describe()
    );
}

#[test]
fn runtime_offers_the_formats_the_layer_must_handle() {
    let Some(sandbox) = sandbox() else { return };
    let run = sandbox.run(&[XR_CLIENT, "--list-formats"], &[]);
    run.assert_success();
    let offered: Vec<&str> = run.stdout.lines().collect();
    for format in [
        "R8G8B8A8_SRGB",
        "B8G8R8A8_SRGB",
        "R8G8B8A8_UNORM",
        "B8G8R8A8_UNORM",
        "R16G16B16A16_UNORM",
        "R16G16B16A16_SFLOAT",
    ] {
        assert!(
            offered.contains(&format),
            "{format} not offered; offered: {offered:?}"
        );
    }
}

/// The default size and format path: the runtime's recommended size and first format.
#[test]
fn client_defaults_follow_the_runtime() {
    let Some(sandbox) = sandbox() else { return };
    let dump = ApiDump::new("client-defaults");
    let env = [vec![("XR_ENABLE_API_LAYERS", ApiDump::LAYER)], dump.env()].concat();
    let run = sandbox.run(&[XR_CLIENT, "--frames", "5"], &env);
    run.assert_success();
    let swapchain = &dump.calls("xrCreateSwapchain")[0];
    // Monado's null compositor: 320x240 per view, R16G16B16A16_UNORM offered first.
    assert_eq!(swapchain.int("createInfo->width"), Some(320));
    assert_eq!(swapchain.int("createInfo->height"), Some(240));
    assert_eq!(
        swapchain.int("createInfo->format"),
        Some(vk_format("R16G16B16A16_UNORM"))
    );
}

/// The validation checks can fail: a deliberate misuse of each API is caught by the layers'
/// logs, and the client's own Vulkan validation count makes it exit non-zero.
#[test]
fn validation_errors_are_caught() {
    let Some(sandbox) = sandbox() else { return };
    let validation = Validation::new("provoked");
    let cmd = [
        XR_CLIENT,
        "--validation",
        "--frames",
        "2",
        "--provoke-xr-validation-error",
        "--provoke-vk-validation-error",
    ];
    let run = sandbox.run(&cmd, &validation.env());
    assert!(
        !run.success(),
        "a Vulkan validation error must fail the client: {}",
        run.describe()
    );
    let xr = validation.xr_errors();
    assert!(
        xr.iter()
            .any(|e| e.contains("VUID-XrSystemGetInfo-formFactor-parameter")),
        "{xr:?}"
    );
    let vk = validation.vk_errors();
    assert!(
        vk.iter()
            .any(|e| e.contains("VUID-VkBufferCreateInfo-size-00912")),
        "{vk:?}"
    );
}

/// hello_xr, the Khronos sample app, reaches FOCUSED and submits frames at the null compositor's
/// 20 Hz for the 4 seconds its stdin stays open.
#[test]
fn hello_xr_reaches_focused_and_submits_frames() {
    let Some(sandbox) = sandbox() else { return };
    let validation = Validation::new("hello_xr").with_xr_layer(ApiDump::LAYER);
    let dump = ApiDump::new("hello_xr");
    let env = [validation.env(), dump.env()].concat();
    let run = sandbox.run(&["sh", "-c", "sleep 4 | hello_xr -g Vulkan2"], &env);
    run.assert_success();
    let output = format!("{}{}", run.stdout, run.stderr);
    assert!(
        output.contains("XR_SESSION_STATE_FOCUSED"),
        "{}",
        run.describe()
    );
    let frames = dump.calls("xrEndFrame");
    // 4 s at 20 Hz is 80; start-up takes a fraction of a second, a busy machine may drop some.
    assert!(
        (30..=100).contains(&frames.len()),
        "{} xrEndFrame calls in 4 s",
        frames.len()
    );
    let full = frames
        .iter()
        .filter(|f| f.int("frameEndInfo->layers[0]->viewCount") == Some(2))
        .count();
    assert!(
        full >= 30,
        "only {full} frames carried a 2-view projection layer"
    );
    validation.assert_clean();
}

#[test]
fn sandbox_returns_the_command_status_and_passes_the_environment() {
    let Some(sandbox) = sandbox() else { return };
    let run = sandbox.run(
        &["sh", "-c", "echo \"$XR_TEST_VALUE\"; exit 7"],
        &[("XR_TEST_VALUE", "seen inside")],
    );
    assert_eq!(run.status.code(), Some(7), "{}", run.describe());
    assert_eq!(run.stdout.trim(), "seen inside");
}

/// Runs get a fresh machine's soft limit of open files (1024), whatever the host's: a runtime
/// or layer that needs more fails here too, not only on a newcomer's machine.
#[test]
fn sandbox_runs_with_a_fresh_machines_open_file_limit() {
    let Some(sandbox) = sandbox() else { return };
    let run = sandbox.run(&["sh", "-c", "ulimit -Sn"], &[]);
    run.assert_success();
    let limit: u64 = run.stdout.trim().parse().expect("a number");
    assert!(
        limit <= 1024,
        "soft open-file limit {limit} inside the sandbox"
    );
}

/// The contrastxr layer is installed as an implicit layer, as for a user: the loader finds the
/// manifest (and leaves the layer off while CONTRASTXR is unset).
#[test]
fn sandbox_installs_the_contrastxr_implicit_layer_manifest() {
    let Some(sandbox) = sandbox() else { return };
    let lib = "/nonexistent/libcontrastxr.so";
    let env = [("CONTRASTXR_LAYER_LIB", lib), ("XR_LOADER_DEBUG", "info")];
    let run = sandbox.run(&[XR_CLIENT, "--list-formats"], &env);
    run.assert_success();
    let output = format!("{}{}", run.stdout, run.stderr);
    assert!(
        output.contains("implicit.d/contrastxr.json is disabled"),
        "{}",
        run.describe()
    );
    // With CONTRASTXR set the loader tries to load it, and says the library is missing.
    let env = [
        ("CONTRASTXR_LAYER_LIB", lib),
        ("XR_LOADER_DEBUG", "info"),
        ("CONTRASTXR", "1"),
    ];
    let run = sandbox.run(&[XR_CLIENT, "--list-formats"], &env);
    let output = format!("{}{}", run.stdout, run.stderr);
    assert!(
        output.contains(&format!("library {lib} does not appear to exist")),
        "{}",
        run.describe()
    );
}

#[test]
fn two_sandbox_runs_at_once_do_not_collide() {
    let Some(sandbox) = sandbox() else { return };
    let runs = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|_| s.spawn(|| sandbox.run(&[XR_CLIENT, "--frames", "30"], &[])))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("run thread"))
            .collect::<Vec<_>>()
    });
    for run in runs {
        run.assert_success();
    }
}
