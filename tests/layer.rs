//! The contrastxr layer inside real OpenXR apps on the real Monado runtime (sandbox), with the
//! OpenXR core validation layer and the Vulkan validation layer (synchronisation validation
//! too) on. The layer's captures are checked against the CPU reference, computed here from the
//! captured display and background, within the tolerance of docs/algorithm.md, Conformance.

mod common;

use common::capture_check::{
    assert_follows_the_video, capture_dir, captures, check_view, sample, video_dir, Captured,
};
use common::{sandbox, scratch_file, ApiDump, SandboxRun, Validation, SYNC_VALIDATION, XR_CLIENT};
use contrastxr::image::RgbaImage;
use std::path::{Path, PathBuf};

/// The formats Monado offers (A2B10G10R10 it does not).
const FORMATS: [&str; 6] = [
    "R8G8B8A8_SRGB",
    "B8G8R8A8_SRGB",
    "R8G8B8A8_UNORM",
    "B8G8R8A8_UNORM",
    "R16G16B16A16_UNORM",
    "R16G16B16A16_SFLOAT",
];

/// Runs `cmd` with validation (core + Vulkan incl. synchronisation) and the layer's `env`.
fn run_validated(
    tag: &str,
    cmd: &[&str],
    env: &[(&str, &str)],
) -> Option<(SandboxRun, Validation)> {
    let sandbox = sandbox()?;
    let validation = Validation::new(tag);
    let mut all = validation.env();
    all.push(("VK_KHRONOS_VALIDATION_VALIDATE_SYNC", "true"));
    all.extend_from_slice(env);
    let run = sandbox.run(cmd, &all);
    Some((run, validation))
}

/// [`run_validated`], then: the run succeeded, validation stayed clean, and the layer logged
/// `line`.
fn run_clean(tag: &str, cmd: &[&str], env: &[(&str, &str)], line: &str) -> Option<SandboxRun> {
    let (run, validation) = run_validated(tag, cmd, env)?;
    run.assert_success();
    validation.assert_clean();
    assert!(run.stderr.contains(line), "no {line:?}: {}", run.describe());
    Some(run)
}

/// The layer's variables for an enhancing run with captures into `dir`.
fn layer_env(dir: &Path, background: &str) -> Vec<(String, String)> {
    vec![
        ("CONTRASTXR".into(), "1".into()),
        ("CONTRASTXR_FORCE".into(), "1".into()),
        // The captures are compared with the CPU reference: no indicator text in them.
        ("CONTRASTXR_INDICATOR".into(), "0".into()),
        ("CONTRASTXR_BACKGROUND".into(), background.into()),
        (
            "CONTRASTXR_CAPTURE_DIR".into(),
            dir.to_string_lossy().into_owned(),
        ),
        ("CONTRASTXR_CAPTURE_SKIP".into(), "3".into()),
        ("CONTRASTXR_CAPTURE_FRAMES".into(), "2".into()),
    ]
}

fn as_refs(v: &[(String, String)]) -> Vec<(&str, &str)> {
    v.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
}

/// How the layer enhances the views of a swapchain format on Monado with `in_place` (None:
/// the default, auto): in place where the runtime grants storage usage (its UNORM and float
/// formats), else through an image of the layer's own (Monado refuses storage usage on sRGB
/// formats, which have no storage support on the device; the layer views only RGBA8 and RGBA16
/// float images in place); `off`, and auto on lavapipe (a CPU driver), through a buffer.
fn expected_path(format: &str, in_place: Option<&str>) -> &'static str {
    match (in_place, format) {
        (Some("on"), "R8G8B8A8_UNORM" | "R16G16B16A16_SFLOAT") => "in-place",
        (Some("on"), _) => "image-copy",
        _ => "copy",
    }
}

fn client_through_layer(format: &str, layout: &str, in_place: Option<&str>) {
    let path = expected_path(format, in_place);
    let tag = format!(
        "layer-{format}-{layout}-{path}-{}",
        in_place.unwrap_or("auto")
    );
    let extra: Vec<(&str, &str)> = in_place
        .map(|v| ("CONTRASTXR_IN_PLACE", v))
        .into_iter()
        .collect();
    let Some((_, views)) = small_client_run(&tag, (format, layout, "12"), &extra, path) else {
        return;
    };
    // The two views are different images (view 1's pattern differs) at their own rects/layers.
    let key = |c: &Captured| {
        (
            c.json["rect"]["x"].as_i64(),
            c.json["image_array_index"].as_u64(),
        )
    };
    assert_ne!(
        key(&views[0]),
        key(&views[1]),
        "both views captured from the same region"
    );
}

/// The client through the layer under validation for `frames` frames of two 160x120 views of
/// `format` in `layout`, with `extra` variables, capturing two frames: its run and the four
/// captured views, each of which took `path` and conforms to the CPU reference with over 1000
/// pixels changed.
fn small_client_run(
    tag: &str,
    (format, layout, frames): (&str, &str, &str),
    extra: &[(&str, &str)],
    path: &str,
) -> Option<(SandboxRun, Vec<Captured>)> {
    let dir = capture_dir(tag);
    let mut env = layer_env(&dir, &format!("image:{}", sample("background-meadow.png")));
    env.extend(extra.iter().map(|(k, v)| (k.to_string(), v.to_string())));
    let cmd = [
        XR_CLIENT,
        "--validation",
        "--json",
        "--frames",
        frames,
        "--size",
        "160x120",
        "--format",
        format,
        "--layout",
        layout,
    ];
    let line = "processing frames (2 views per frame)";
    let run = run_clean(tag, &cmd, &as_refs(&env), line)?;
    let views = captures(&dir);
    assert_eq!(
        views.len(),
        4,
        "2 frames x 2 views captured in {}",
        dir.display()
    );
    for c in &views {
        assert_eq!(c.json["path"], path, "{format} {layout}");
        let changed = check_view(c);
        assert!(
            changed > 1000,
            "{format} {layout}: the method changed only {changed} pixels"
        );
    }
    Some((run, views))
}

/// One test per format (they run in parallel), each through both layouts and both paths
/// (in place where the runtime allows it, and always through a copy).
macro_rules! through_the_layer {
    ($($name:ident: $format:literal,)*) => {$(
        #[test]
        fn $name() {
            for layout in ["array", "side-by-side"] {
                for in_place in ["on", "off"] {
                    client_through_layer($format, layout, Some(in_place));
                }
            }
        }
    )*};
}

through_the_layer! {
    layer_enhances_rgba8_srgb: "R8G8B8A8_SRGB",
    layer_enhances_bgra8_srgb: "B8G8R8A8_SRGB",
    layer_enhances_rgba8_unorm: "R8G8B8A8_UNORM",
    layer_enhances_bgra8_unorm: "B8G8R8A8_UNORM",
    layer_enhances_rgba16_unorm: "R16G16B16A16_UNORM",
    layer_enhances_rgba16_float: "R16G16B16A16_SFLOAT",
}

/// Views wide enough for the default mapping to let a group's pixels share their texel reads
/// (1024 pixels over the 960-wide background: 0.61 texel per pixel, gpu/core/shared_fetch.rs), in
/// place and through a copy: frames captured after 30, when the shared-fetch variant, built
/// behind the frame's pipelines, serves the views (from the third frame in a run on lavapipe),
/// conform to the CPU reference.
#[test]
fn wide_views_with_shared_texel_reads_conform() {
    for in_place in ["on", "off"] {
        let format = "R8G8B8A8_UNORM";
        let path = expected_path(format, Some(in_place));
        let tag = format!("layer-shared-fetch-{path}");
        let dir = capture_dir(&tag);
        let mut env = layer_env(&dir, &format!("image:{}", sample("background-meadow.png")));
        env.retain(|(k, _)| k != "CONTRASTXR_CAPTURE_SKIP");
        env.push(("CONTRASTXR_CAPTURE_SKIP".into(), "30".into()));
        env.push(("CONTRASTXR_IN_PLACE".into(), in_place.into()));
        let cmd = [
            XR_CLIENT,
            "--validation",
            "--json",
            "--frames",
            "40",
            "--size",
            "1024x768",
            "--format",
            format,
        ];
        let line = "processing frames (2 views per frame)";
        let Some(_) = run_clean(&tag, &cmd, &as_refs(&env), line) else {
            return;
        };
        let views = captures(&dir);
        assert_eq!(views.len(), 4, "2 frames x 2 views in {}", dir.display());
        for c in &views {
            assert_eq!(c.json["path"], path);
            assert!(check_view(c) > 100_000, "{path}: few pixels changed");
        }
    }
}

/// `copy_back = "tiles"` on sRGB swapchains (Monado refuses them storage usage, so their views
/// go through an image of the layer's own): only the tiles the enhancement listed are drawn
/// back into the app's images, on the app's device under validation. The captures read the
/// regions back from the app's images after the draw (`"path": "image-copy-tiles"`), so what
/// the check holds to the CPU reference is what reached the app's images; `pipelines = "wait"`
/// has every frame drawn.
#[test]
fn listed_tiles_drawn_back_reach_the_app_images() {
    for (format, layout) in [
        ("R8G8B8A8_SRGB", "array"),
        ("B8G8R8A8_SRGB", "side-by-side"),
    ] {
        let Some(run) = tiles_run(format, layout, None) else {
            return;
        };
        assert!(
            run.stderr
                .contains("2 of them with the listed tiles drawn back"),
            "{}",
            run.describe()
        );
    }
}

/// `copy_in = "sampled"` on sRGB swapchains: the layer adds sampled usage to them, reads each
/// region through a sampled view of the app's image instead of copying it in, and draws the
/// listed tiles back, on the app's device under validation (synchronisation too); the captures
/// (`"path": "sampled-tiles"`, read back from the app's images after the draw) conform to the
/// CPU reference.
#[test]
fn sampled_reads_reach_the_app_images() {
    for (format, layout) in [
        ("R8G8B8A8_SRGB", "side-by-side"),
        ("B8G8R8A8_SRGB", "array"),
    ] {
        let tag = format!("layer-sampled-{format}");
        let extra = [
            ("CONTRASTXR_IN_PLACE", "on"),
            ("CONTRASTXR_COPY_IN", "sampled"),
            ("CONTRASTXR_PIPELINES", "wait"),
            SYNC_VALIDATION,
        ];
        let Some((run, _)) = small_client_run(&tag, (format, layout, "8"), &extra, "sampled-tiles")
        else {
            return;
        };
        let line =
            "2 of them with the listed tiles drawn back, 2 of those read through a sampled view";
        assert!(run.stderr.contains(line), "{}", run.describe());
    }
}

/// A sampled read whose tiles cannot be drawn back (fault point `write-back-build`) copies the
/// region in and back, as the image-copy path does (`"path": "image-copy"`, still enhanced
/// and conforming).
#[test]
fn sampled_reads_that_cannot_draw_back_copy_the_region_in_and_back() {
    let extra = [
        ("CONTRASTXR_IN_PLACE", "on"),
        ("CONTRASTXR_COPY_IN", "sampled"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_FAULT", "write-back-build"),
    ];
    let tag = "layer-sampled-fault";
    let format = ("R8G8B8A8_SRGB", "array", "8");
    let Some((run, _)) = small_client_run(tag, format, &extra, "image-copy") else {
        return;
    };
    assert!(run.stderr.contains("the listed tiles cannot be drawn back"));
}

/// A write-back that cannot be built (fault point `write-back-build`): the views copy the
/// region back (`"path": "image-copy"`, still enhanced and conforming), and the layer says
/// why in one line.
#[test]
fn tiles_that_cannot_be_drawn_back_copy_the_region_back() {
    let Some(run) = tiles_run("R8G8B8A8_SRGB", "array", Some("write-back-build")) else {
        return;
    };
    let about = run
        .stderr
        .lines()
        .filter(|l| l.contains("the listed tiles cannot be drawn back"))
        .count();
    assert_eq!(about, 1, "{}", run.describe());
    assert!(run.stderr.contains("fault injected at write-back-build"));
}

/// A run with `copy_back = "tiles"` (and `fault`), its four captured views checked against the
/// CPU reference, each having taken `image-copy-tiles`, or `image-copy` under a fault.
fn tiles_run(format: &str, layout: &str, fault: Option<&str>) -> Option<SandboxRun> {
    let tag = format!("layer-tiles-{format}-{}", fault.unwrap_or("none"));
    let mut extra = vec![
        ("CONTRASTXR_IN_PLACE", "on"),
        ("CONTRASTXR_COPY_BACK", "tiles"),
        ("CONTRASTXR_PIPELINES", "wait"),
    ];
    extra.extend(fault.map(|point| ("CONTRASTXR_FAULT", point)));
    let path = match fault {
        None => "image-copy-tiles",
        Some(_) => "image-copy",
    };
    small_client_run(&tag, (format, layout, "8"), &extra, path).map(|(run, _)| run)
}

/// `in_place = "auto"` (the default) on lavapipe, a CPU driver: the copy path, even where the
/// runtime would grant storage usage.
#[test]
fn auto_keeps_a_cpu_driver_on_the_copy_path() {
    client_through_layer("R8G8B8A8_UNORM", "array", None);
}

#[test]
fn formats_list_matches_the_runtime() {
    // Guards FORMATS above: if Monado starts offering another format, test it too.
    let Some(sandbox) = sandbox() else { return };
    let run = sandbox.run(&[XR_CLIENT, "--list-formats"], &[]);
    run.assert_success();
    for f in FORMATS {
        assert!(
            run.stdout.contains(f),
            "runtime no longer offers {f}: {}",
            run.stdout
        );
    }
}

/// The client's re-read of each image when it acquires it again found no change made to it.
#[track_caller]
fn assert_frames_untouched(run: &SandboxRun, why: &str) {
    let report = run.client_report();
    assert!(report["frames_checked"].as_u64().unwrap() >= 5, "{report}");
    assert_eq!(report["frames_modified"], serde_json::json!([]), "{why}");
}

/// Lines the layer printed (each starts with "contrastxr:").
fn layer_lines(run: &SandboxRun) -> Vec<&str> {
    run.stderr
        .lines()
        .filter(|l| l.starts_with("contrastxr:"))
        .collect()
}

/// An app that acquires and waits for its next image before xrEndFrame of the current frame (a
/// render thread running ahead) still has every frame enhanced: the client reads each image back
/// when it renders into it again and finds every earlier frame changed, and the layer's
/// captures (one per frame) match the CPU reference. With the layer off nothing changes.
#[test]
fn pipelined_apps_have_every_frame_enhanced() {
    let tag = "layer-pipelined";
    let dir = capture_dir(tag);
    let mut env = layer_env(&dir, &format!("image:{}", sample("background-meadow.png")));
    env.retain(|(k, _)| {
        !k.starts_with("CONTRASTXR_CAPTURE_SKIP") && !k.starts_with("CONTRASTXR_CAPTURE_FRAMES")
    });
    env.push(("CONTRASTXR_CAPTURE_FRAMES".into(), "1000".into()));
    let cmd = [
        XR_CLIENT,
        "--validation",
        "--json",
        "--frames",
        "12",
        "--size",
        "160x120",
        "--pipelined",
        "--check-untouched",
    ];
    let Some(run) = run_clean(tag, &cmd, &as_refs(&env), "pipelined renderer") else {
        return;
    };
    let report = run.client_report();
    let checked = report["frames_checked"].as_u64().unwrap();
    assert!(checked >= 5, "{report}");
    assert_eq!(
        report["frames_modified"].as_array().unwrap().len() as u64,
        checked,
        "every frame read back again must have been enhanced: {report}\nlayer: {:#?}",
        layer_lines(&run)
    );
    let views = captures(&dir);
    let submitted = report["frames_submitted"].as_u64().unwrap() as usize;
    assert_eq!(
        views.len(),
        2 * submitted,
        "2 views of every frame captured"
    );
    for c in &views {
        assert!(check_view(c) > 1000, "a frame was barely changed");
    }
    let off = sandbox().unwrap().run(&cmd, &[("CONTRASTXR", "0")]);
    off.assert_success();
    assert_frames_untouched(
        &off,
        "with the layer off the client's frames stay as written",
    );
}

#[test]
fn off_values_pass_everything_through() {
    for value in ["0", "false", "off", ""] {
        let tag = format!(
            "layer-off-{}",
            if value.is_empty() { "empty" } else { value }
        );
        let dir = capture_dir(&tag);
        let dump = ApiDump::new(&tag);
        let mut env = layer_env(&dir, "color:#e0d020");
        env[0].1 = value.into();
        env.push(("XR_ENABLE_API_LAYERS".into(), ApiDump::LAYER.into()));
        let mut env = as_refs(&env);
        env.extend(dump.env());
        let Some(sandbox) = sandbox() else { return };
        let run = sandbox.run(
            &[
                XR_CLIENT,
                "--json",
                "--frames",
                "8",
                "--format",
                "R8G8B8A8_SRGB",
            ],
            &env,
        );
        run.assert_success();
        let lines = layer_lines(&run);
        assert_eq!(
            lines.len(),
            1,
            "CONTRASTXR={value:?}: expected one log line, got {lines:?}"
        );
        assert!(lines[0].contains(" off "), "{lines:?}");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "captured while off"
        );
        // api_dump sits below the layer: the runtime saw the app's own usage flags (17 =
        // COLOR_ATTACHMENT | TRANSFER_DST), not the TRANSFER_SRC the layer adds when on.
        let created = dump.calls("xrCreateSwapchain");
        assert!(!created.is_empty());
        for call in created {
            assert_eq!(
                call.int("createInfo->usageFlags"),
                Some(17),
                "CONTRASTXR={value:?}"
            );
        }
    }
}

#[test]
fn hello_xr_runs_through_the_layer_for_ten_seconds() {
    let dir = capture_dir("layer-hello-xr");
    let env = layer_env(
        &dir,
        &format!("image:{}", sample("background-yellow-wall.png")),
    );
    // At least 10 s, then until the two frames are captured (the pipelines may be cold).
    let script = format!(
        "{} | hello_xr -g Vulkan2",
        common::stdin_until_captured(&dir, 4, 10)
    );
    let cmd = ["bash", "-c", script.as_str()];
    let Some((run, validation)) = run_validated("layer-hello-xr", &cmd, &as_refs(&env)) else {
        return;
    };
    run.assert_success();
    validation.assert_clean();
    let lines = layer_lines(&run);
    assert!(
        lines
            .iter()
            .any(|l| l.contains("processing frames (2 views per frame)")),
        "{lines:?}"
    );
    let views = captures(&dir);
    assert_eq!(views.len(), 4);
    for c in &views {
        assert!(check_view(c) > 1000);
    }
}

/// An explicit manifest for the freshly built library, so the layer's position among other
/// explicit layers can be chosen with XR_ENABLE_API_LAYERS.
fn explicit_manifest_dir() -> PathBuf {
    let dir = scratch_file("explicit-layer");
    std::fs::create_dir_all(&dir).unwrap();
    let lib = Path::new(XR_CLIENT).with_file_name("libcontrastxr.so");
    let template = include_str!("../layer-manifest/contrastxr-explicit.json");
    let text = template.replace("../target/release/libcontrastxr.so", &lib.to_string_lossy());
    std::fs::write(dir.join("contrastxr.json"), text).unwrap();
    dir
}

#[test]
fn stacks_with_api_dump_and_core_validation_on_either_side() {
    let ours = "XR_APILAYER_CONTRASTXR_color_contrast";
    let (dump_l, core) = (ApiDump::LAYER, "XR_APILAYER_LUNARG_core_validation");
    let path = format!(
        "{}:/usr/share/openxr/1/api_layers/explicit.d",
        explicit_manifest_dir().display()
    );
    // Core validation stays above api_dump: below it, it flags api_dump's own
    // xrStructureTypeToString(XR_TYPE_GRAPHICS_BINDING_VULKAN_KHR) calls for a Vulkan2 app (an
    // interaction of those two layers, not of contrastxr).
    for (name, order) in [
        ("before", [core, dump_l, ours]),
        ("after", [ours, core, dump_l]),
    ] {
        let tag = format!("layer-stack-{name}");
        let dir = capture_dir(&tag);
        let (dump, validation) = (ApiDump::new(&tag), Validation::new(&tag));
        let layers = order.join(":");
        let mut env = layer_env(&dir, "color:#e0d020");
        env.retain(|(k, _)| k != "CONTRASTXR"); // explicit: no implicit copy; unset means on
        env.push(("XR_API_LAYER_PATH".into(), path.clone()));
        let mut all: Vec<(&str, &str)> = validation
            .env()
            .into_iter()
            .filter(|(k, _)| *k != "XR_ENABLE_API_LAYERS")
            .collect();
        all.push(("XR_ENABLE_API_LAYERS", layers.as_str()));
        all.extend(dump.env());
        all.extend(as_refs(&env));
        let Some(sandbox) = sandbox() else { return };
        let run = sandbox.run(
            &[
                XR_CLIENT,
                "--validation",
                "--json",
                "--frames",
                "10",
                "--format",
                "B8G8R8A8_SRGB",
            ],
            &all,
        );
        run.assert_success();
        validation.assert_clean();
        assert!(
            run.stderr.contains("processing frames"),
            "{name}: {}",
            run.describe()
        );
        assert!(dump.calls("xrEndFrame").len() >= 10, "{name}");
        for c in captures(&dir) {
            assert!(check_view(&c) > 1000, "{name}");
        }
    }
}

#[test]
fn captures_follow_a_changing_video_background() {
    let tag = "layer-video";
    let dir = capture_dir(tag);
    let video = video_dir(tag, 6);
    let mut env = layer_env(&dir, &format!("video:{}", video.display()));
    env.retain(|(k, _)| k != "CONTRASTXR_CAPTURE_FRAMES");
    env.push(("CONTRASTXR_CAPTURE_FRAMES".into(), "12".into()));
    let cmd = [
        XR_CLIENT,
        "--validation",
        "--json",
        "--frames",
        "24",
        "--size",
        "128x96",
        "--format",
        "R8G8B8A8_SRGB",
    ];
    let Some((run, validation)) = run_validated(tag, &cmd, &as_refs(&env)) else {
        return;
    };
    run.assert_success();
    validation.assert_clean();
    // lavapipe samples mapped linear images: the source's texels go straight into them.
    let direct = "live frames' texels are written straight into mapped images the views sample";
    assert!(
        run.stderr.contains(direct),
        "no {direct:?}: {}",
        run.describe()
    );
    // And from the second camera frame on, the source's thread writes them there itself.
    let source = "live frames' texels are written into mapped memory on the camera's thread";
    assert!(
        run.stderr.contains(source),
        "no {source:?}: {}",
        run.describe()
    );
    assert_follows_the_video(&captures(&dir));
}

#[test]
fn quad_layers_are_enhanced_when_configured() {
    let tag = "layer-quad";
    let dir = capture_dir(tag);
    let mut env = layer_env(&dir, "color:#e0d020");
    env.push(("CONTRASTXR_QUAD_LAYERS".into(), "1".into()));
    env.retain(|(k, _)| k != "CONTRASTXR_CAPTURE_FRAMES");
    env.push(("CONTRASTXR_CAPTURE_FRAMES".into(), "1".into()));
    let cmd = [
        XR_CLIENT,
        "--validation",
        "--json",
        "--frames",
        "8",
        "--quad",
        "--format",
        "R8G8B8A8_SRGB",
    ];
    let run = run_clean(
        tag,
        &cmd,
        &as_refs(&env),
        "processing frames (3 views per frame)",
    );
    if run.is_none() {
        return;
    }
    let views = captures(&dir);
    assert_eq!(views.len(), 3, "two projection views and the quad");
    for c in &views {
        assert!(check_view(c) > 100);
    }
}

#[test]
fn two_apps_use_the_layer_at_once() {
    let dir = capture_dir("layer-two-apps");
    let mut env = layer_env(&dir, "color:#e0d020");
    env.retain(|(k, _)| !k.starts_with("CONTRASTXR_CAPTURE"));
    let Some(sandbox) = sandbox() else { return };
    let script = format!(
        "{XR_CLIENT} --frames 40 --format R8G8B8A8_SRGB & a=$!; \
         {XR_CLIENT} --frames 40 --format B8G8R8A8_UNORM --layout side-by-side & b=$!; \
         wait $a && wait $b"
    );
    let run = sandbox.run(&["bash", "-c", &script], &as_refs(&env));
    run.assert_success();
    let processing = layer_lines(&run)
        .iter()
        .filter(|l| l.contains("processing frames"))
        .count();
    assert_eq!(processing, 2, "{}", run.describe());
}

#[test]
fn no_camera_means_pass_through_with_one_line() {
    let tag = "layer-no-camera";
    let dir = capture_dir(tag);
    let dump = ApiDump::new(tag);
    // No V4L2 device exists here, so the default background source finds nothing.
    let mut env = layer_env(&dir, "v4l2:auto");
    env.push(("XR_ENABLE_API_LAYERS".into(), ApiDump::LAYER.into()));
    let mut env = as_refs(&env);
    env.extend(dump.env());
    let Some(sandbox) = sandbox() else { return };
    let run = sandbox.run(
        &[
            XR_CLIENT,
            "--json",
            "--check-untouched",
            "--frames",
            "10",
            "--format",
            "R8G8B8A8_SRGB",
        ],
        &env,
    );
    run.assert_success();
    assert_frames_untouched(&run, "frames were changed");
    let lines = layer_lines(&run);
    let fallback: Vec<_> = lines
        .iter()
        .filter(|l| l.contains("passing frames through"))
        .collect();
    assert_eq!(fallback.len(), 1, "{lines:?}");
    assert!(fallback[0].contains("no V4L2 capture device"), "{lines:?}");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "captured without a background"
    );
    // (The session keeps its GPU set-up so that a background arriving through a config change
    // is picked up, so its swapchains do get the transfer usage; the frames stay untouched.)
    assert!(dump.calls("xrEndFrame").len() >= 10);
}

#[test]
fn background_smoothing_blends_successive_frames() {
    let tag = "layer-smoothing";
    let dir = capture_dir(tag);
    let video = video_dir(tag, 6);
    let originals: Vec<Vec<[u8; 4]>> = (0..6)
        .map(|i| {
            RgbaImage::load_png(&video.join(format!("frame-{i:03}.png")))
                .unwrap()
                .pixels
        })
        .collect();
    let mut env = layer_env(&dir, &format!("video:{}", video.display()));
    env.retain(|(k, _)| k != "CONTRASTXR_CAPTURE_FRAMES");
    env.push(("CONTRASTXR_CAPTURE_FRAMES".into(), "10".into()));
    env.push(("CONTRASTXR_BACKGROUND_SMOOTHING".into(), "0.5".into()));
    let cmd = [
        XR_CLIENT,
        "--json",
        "--frames",
        "20",
        "--size",
        "96x64",
        "--format",
        "R8G8B8A8_SRGB",
    ];
    let Some(sandbox) = sandbox() else { return };
    let run = sandbox.run(&cmd, &as_refs(&env));
    run.assert_success();
    let views = captures(&dir);
    assert_eq!(views.len(), 20);
    let blended = views
        .iter()
        .filter(|c| !originals.contains(&c.camera.pixels))
        .count();
    assert!(
        blended > 0,
        "smoothing on, yet every background used was an unblended video frame"
    );
    for c in &views {
        check_view(c);
    }
}

#[test]
fn opaque_sessions_pass_through_unless_forced() {
    // The simulated HMD offers only OPAQUE; an optical see-through headset is ADDITIVE.
    let tag = "layer-opaque";
    let dir = capture_dir(tag);
    let mut env = layer_env(&dir, "color:#e0d020");
    env.retain(|(k, _)| k != "CONTRASTXR_FORCE");
    let Some(sandbox) = sandbox() else { return };
    let cmd = [
        XR_CLIENT,
        "--json",
        "--check-untouched",
        "--frames",
        "12",
        "--format",
        "R8G8B8A8_SRGB",
    ];
    let run = sandbox.run(&cmd, &as_refs(&env));
    run.assert_success();
    assert_frames_untouched(&run, "an OPAQUE session's frames were changed");
    let lines = layer_lines(&run);
    let blend: Vec<_> = lines
        .iter()
        .filter(|l| l.contains("not ADDITIVE"))
        .collect();
    assert_eq!(blend.len(), 1, "one line about the blend mode: {lines:?}");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "captured an OPAQUE session"
    );
}
