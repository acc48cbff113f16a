//! The perceptual method inside real OpenXR sessions on the real Monado runtime (sandbox): the
//! project's client through the layer with `method = "perceptual"` outdoors (5000 cd/m², where
//! it changes most content), Vulkan (through a buffer and through an image of the layer's own)
//! and OpenGL. Each captured view is held to the CPU reference at the view's own frequency
//! (its pixels per degree and camera mapping, from the capture), within the tolerance of
//! docs/algorithm.md, Conformance, with the method visibly at work.

mod common;

use common::capture_check::{capture_dir, captures, check_view, sample};
use common::gl_client::client_opengl;
use common::{layer_lines, sandbox, RUN_TIMEOUT_S, XR_CLIENT};
use std::path::Path;

/// The layer's variables: the perceptual method outdoors, every pixel spending the paper's
/// change (target 1), two frames captured after 3.
fn layer_env(dir: &Path) -> Vec<(String, String)> {
    let background = format!("image:{}", sample("background-meadow.png"));
    [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_PIPELINES", "wait"),
        ("CONTRASTXR_METHOD", "perceptual"),
        ("CONTRASTXR_WORLD_NITS", "5000"),
        ("CONTRASTXR_TARGET_CONTRAST", "1"),
        ("CONTRASTXR_BACKGROUND", &background),
        ("CONTRASTXR_CAPTURE_DIR", &dir.to_string_lossy()),
        ("CONTRASTXR_CAPTURE_SKIP", "3"),
        ("CONTRASTXR_CAPTURE_FRAMES", "2"),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect()
}

fn as_refs(v: &[(String, String)]) -> Vec<(&str, &str)> {
    v.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
}

/// Every captured view in `dir` conforms, on `path`, and the method changed many pixels.
fn check_captures(dir: &Path, path: &str, what: &str) {
    let views = captures(dir);
    assert_eq!(
        views.len(),
        4,
        "{what}: 2 frames x 2 views in {}",
        dir.display()
    );
    for c in &views {
        assert_eq!(c.json["params"]["method"], "perceptual", "{what}");
        assert_eq!(c.json["path"], path, "{what}");
        let ppd = c.json["pixels_per_degree"].as_f64().unwrap_or(0.0);
        assert!(ppd > 0.0, "{what}: pixels per degree {ppd}");
        let changed = check_view(c);
        assert!(
            changed > 1000,
            "{what}: the method changed only {changed} pixels"
        );
    }
}

#[test]
fn vulkan_sessions_get_the_perceptual_method_within_the_reference() {
    for (in_place, path) in [("off", "copy"), ("on", "image-copy")] {
        let Some(sandbox) = sandbox() else {
            return;
        };
        let tag = format!("perceptual-vulkan-{path}");
        let dir = capture_dir(&tag);
        let mut env = layer_env(&dir);
        env.push(("CONTRASTXR_IN_PLACE".into(), in_place.into()));
        let cmd = [
            XR_CLIENT,
            "--json",
            "--frames",
            "12",
            "--size",
            "160x120",
            "--format",
            "R8G8B8A8_SRGB",
        ];
        let run = sandbox.run(&cmd, &as_refs(&env));
        run.assert_success();
        assert!(
            layer_lines(&run)
                .iter()
                .any(|l| l.contains("processing frames (2 views per frame)")),
            "{tag}: {}",
            run.describe()
        );
        check_captures(&dir, path, &tag);
    }
}

#[test]
fn opengl_sessions_get_the_perceptual_method_within_the_reference() {
    let dir = capture_dir("perceptual-opengl");
    let env = layer_env(&dir);
    let Some(run) = client_opengl("R8G8B8A8_SRGB", 12, &as_refs(&env), &[], RUN_TIMEOUT_S) else {
        return;
    };
    run.assert_success();
    check_captures(&dir, "copy", "opengl");
}
