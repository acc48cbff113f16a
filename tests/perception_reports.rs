//! What the layer reports of the perceived contrast (docs/algorithm.md, *What it reports*),
//! inside the project's test client on the real Monado runtime (sandbox): every capture's JSON
//! carries the perceptual model's report, which `contrastxr evaluate --json` computes again
//! from the capture's own PNG files; and when most content is out of reach against a bright
//! world, the layer's log says so, at most once per (test-shortened) minute.

mod common;

use common::capture_check::{capture_dir, captures, sample, Captured};
use common::{layer_lines, sandbox, SandboxRun, CLI, XR_CLIENT};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The keys `contrastxr evaluate --json` adds for the perceived contrast.
const NUMBERS: [&str; 10] = [
    "perceived_contrast_before",
    "perceived_contrast_after",
    "perceived_contrast_gain",
    "perceived_contrast_log2_gain",
    "target_contrast",
    "left_alone_fraction",
    "brought_to_target_fraction",
    "out_of_reach_fraction",
    "mean_world_luminance",
    "pixels_per_degree",
];

fn layer_env(
    dir: Option<&Path>,
    background: &str,
    extra: &[(&str, &str)],
) -> Vec<(String, String)> {
    let mut env: Vec<(String, String)> = [
        ("CONTRASTXR", "1"),
        ("CONTRASTXR_FORCE", "1"),
        ("CONTRASTXR_INDICATOR", "0"),
        ("CONTRASTXR_BACKGROUND", background),
    ]
    .iter()
    .chain(extra)
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    if let Some(dir) = dir {
        env.push((
            "CONTRASTXR_CAPTURE_DIR".into(),
            dir.to_string_lossy().into_owned(),
        ));
        env.push(("CONTRASTXR_CAPTURE_SKIP".into(), "3".into()));
        env.push(("CONTRASTXR_CAPTURE_FRAMES".into(), "1".into()));
    }
    env
}

/// Runs the test client for `frames` frames at 128x96 in `format` through the layer: views
/// small enough for their report to take every pixel (`perception_step` 1).
fn run_client(format: &str, frames: u32, env: &[(String, String)]) -> Option<SandboxRun> {
    let sandbox = sandbox()?;
    let env: Vec<(&str, &str)> = env.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    let frames = frames.to_string();
    let cmd = [
        XR_CLIENT, "--json", "--frames", &frames, "--size", "128x96", "--format", format,
    ];
    let run = sandbox.run(&cmd, &env);
    run.assert_success();
    Some(run)
}

/// A capture's file next to its JSON.
fn file(dir: &Path, c: &Captured, suffix: &str) -> PathBuf {
    let (frame, view) = (c.json["frame"].as_u64(), c.json["view"].as_u64());
    dir.join(format!(
        "frame-{}-view-{}{suffix}",
        frame.unwrap(),
        view.unwrap()
    ))
}

/// `contrastxr evaluate --json` on a capture's PNG files at the view's pixels per degree.
fn evaluate(dir: &Path, c: &Captured) -> serde_json::Value {
    let ppd = c.json["pixels_per_degree"].as_f64().unwrap().to_string();
    let path = |suffix| file(dir, c, suffix).to_string_lossy().into_owned();
    let o = std::process::Command::new(CLI)
        .args(["evaluate", "--json", "--ppd", &ppd, "--display"])
        .arg(path("-display.png"))
        .arg("--background")
        .arg(path("-background.png"))
        .arg("--enhanced")
        .arg(path("-output.png"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// Every key there and plausible: c' in [0, 1), the gain their ratio, the classes shares that
/// sum to 1, the frequency the blur's at the view's pixels per degree, the world behind the
/// content what a white-balanced meadow gives through the lens.
fn assert_plausible(c: &Captured) {
    let j = &c.json;
    let f = |k: &str| j[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {j}"));
    for k in NUMBERS {
        assert!(f(k).is_finite(), "{k}: {j}");
    }
    let (before, after) = (
        f("perceived_contrast_before"),
        f("perceived_contrast_after"),
    );
    assert!(
        (0.0..1.0).contains(&before) && (0.0..1.0).contains(&after),
        "{j}"
    );
    let gain = after / before.max(1e-4);
    assert!(
        (f("perceived_contrast_gain") - gain).abs() <= 1e-9 * gain,
        "{j}"
    );
    let log2 = f("perceived_contrast_log2_gain") - gain.log2();
    assert!(log2.abs() < 1e-9, "{j}");
    let classes = [
        "left_alone_fraction",
        "brought_to_target_fraction",
        "out_of_reach_fraction",
    ];
    assert!(classes.iter().all(|k| (0.0..=1.0).contains(&f(k))), "{j}");
    let sum: f64 = classes.iter().map(|k| f(k)).sum();
    assert!((sum - 1.0).abs() < 1e-9, "{j}");
    assert_eq!(j["frequency"], "blur", "{j}");
    let cpd = j["frequency_cpd"][0].as_f64().unwrap();
    assert!((1.0..=30.0).contains(&cpd), "{j}");
    // The client's views are 128 px wide: 0.1 to 10 px per degree at the axis is a field of
    // view between about 13 and 170 degrees, as a headset's.
    assert!((0.1..10.0).contains(&f("pixels_per_degree")), "{j}");
    assert_eq!(j["perception_step"], 1, "every pixel of a small view: {j}");
    // A meadow under 1000 cd/m^2 through a lens of 0.4: between dark soil and white sky.
    assert!((10.0..400.0).contains(&f("mean_world_luminance")), "{j}");
}

/// The layer's report against `evaluate`'s on the same capture, within `tolerance` for the
/// means (0 for an sRGB format, whose PNGs hold its bytes) and `share` for the classes.
fn assert_as_evaluate(dir: &Path, c: &Captured, tolerance: f64, share: f64) {
    let (layer, tool) = (&c.json, evaluate(dir, c));
    let close = |k: &str, rel: f64| {
        let (a, b) = (layer[k].as_f64().unwrap(), tool[k].as_f64().unwrap());
        assert!(
            (a - b).abs() <= rel * b.abs() + 1e-12,
            "{k}: layer {a}, evaluate {b}"
        );
    };
    for k in [
        "perceived_contrast_before",
        "perceived_contrast_after",
        "perceived_contrast_gain",
    ] {
        close(k, tolerance.max(1e-9));
    }
    close("mean_world_luminance", tolerance.max(1e-9) / 10.0);
    close("target_contrast", 0.0);
    for k in [
        "left_alone_fraction",
        "brought_to_target_fraction",
        "out_of_reach_fraction",
    ] {
        let (a, b) = (layer[k].as_f64().unwrap(), tool[k].as_f64().unwrap());
        assert!(
            (a - b).abs() <= share + 1e-12,
            "{k}: layer {a}, evaluate {b}"
        );
    }
    assert_eq!(layer["frequency"], tool["frequency"]);
    let cpd = |j: &serde_json::Value| j["frequency_cpd"][0].as_f64().unwrap();
    assert!((cpd(layer) - cpd(&tool)).abs() < 1e-12, "{layer} {tool}");
}

/// Each capture's JSON has the perception report's keys, plausible and as `contrastxr
/// evaluate --json` finds them on the capture's PNG files (the same pixels for an sRGB
/// swapchain; a float one's within its PNG's 8-bit steps).
#[test]
fn captures_report_the_perceived_contrast_as_evaluate_does() {
    for (format, tolerance, share) in [
        ("R8G8B8A8_SRGB", 0.0, 0.0),
        ("R16G16B16A16_SFLOAT", 0.02, 0.02),
    ] {
        let dir = capture_dir(&format!("perception-{format}"));
        let meadow = format!("image:{}", sample("background-meadow.png"));
        let env = layer_env(Some(&dir), &meadow, &[]);
        if run_client(format, 8, &env).is_none() {
            return;
        }
        let views = captures(&dir);
        assert_eq!(
            views.len(),
            2,
            "one frame of two views in {}",
            dir.display()
        );
        for c in &views {
            // The views take the default manual mapping here, as `evaluate` does.
            let manual = contrastxr::algorithm::Params::default()
                .camera_mapping()
                .rows;
            let m = &c.json["camera_mapping"];
            for (r, row) in manual.iter().enumerate() {
                for (k, v) in row.iter().enumerate() {
                    let a = m[r][k].as_f64().unwrap();
                    assert!((a - v).abs() < 1e-12, "{format}: mapping {m}");
                }
            }
            assert_plausible(c);
            assert_as_evaluate(&dir, c, tolerance, share);
        }
    }
}

const ADVICE: &str = "most content is out of reach";

/// Against a white world of 50 000 cd/m^2 (20 000 at the eye) most content is out of reach:
/// the layer says so with what would help, from its own read-back of the views (no capture
/// folder), and no more often than once per minute (here the fault point `short-minute`'s
/// 2 s). Against a dark world, or with the real minute in a run shorter than it, it says
/// nothing.
#[test]
fn most_content_out_of_reach_is_said_at_most_once_a_minute() {
    let bright = [
        ("CONTRASTXR_WORLD_NITS", "50000"),
        ("CONTRASTXR_FAULT", "short-minute"),
        ("CONTRASTXR_LOG", "debug"),
    ];
    let started = Instant::now();
    let Some(run) = run_client(
        "R8G8B8A8_SRGB",
        140,
        &layer_env(None, "color:#ffffff", &bright),
    ) else {
        return;
    };
    let took = started.elapsed();
    let said: Vec<String> = layer_lines(&run)
        .into_iter()
        .filter(|l| l.contains(ADVICE))
        .collect();
    assert!(!said.is_empty(), "no {ADVICE:?}: {}", run.describe());
    eprintln!("the layer said: {}", said[0]);
    for words in ["display_peak_nits", "transmittance", "world_nits", "50000"] {
        assert!(said[0].contains(words), "{words}: {}", said[0]);
    }
    // Each read-back has two views with most of their content out of reach: one line at
    // most per read-back, and per 2 s.
    let read_backs = run
        .stderr
        .matches("views read back for the out-of-reach check")
        .count();
    let most = took.as_secs_f64() / Duration::from_secs(2).as_secs_f64() + 1.0;
    assert!(
        said.len() <= read_backs && said.len() as f64 <= most,
        "{} lines after {read_backs} read-backs in {took:?}: {said:#?}",
        said.len()
    );
    let dark = [
        ("CONTRASTXR_WORLD_NITS", "20"),
        ("CONTRASTXR_FAULT", "short-minute"),
    ];
    let run = run_client(
        "R8G8B8A8_SRGB",
        140,
        &layer_env(None, "color:#404040", &dark),
    )
    .unwrap();
    assert!(
        run.stderr.contains("processing frames"),
        "{}",
        run.describe()
    );
    assert!(!run.stderr.contains(ADVICE), "{}", run.describe());
    let minute = [("CONTRASTXR_WORLD_NITS", "50000")];
    let run = run_client(
        "R8G8B8A8_SRGB",
        140,
        &layer_env(None, "color:#ffffff", &minute),
    )
    .unwrap();
    assert!(
        run.stderr.contains("processing frames"),
        "{}",
        run.describe()
    );
    assert!(!run.stderr.contains(ADVICE), "{}", run.describe());
}
