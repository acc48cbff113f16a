//! The `contrastxr` binary on the sample scenes, CPU engine: outputs checked against the
//! inputs independently (black stays black, lambda_e 0 changes nothing, metric consistency),
//! and the error messages and exit codes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use contrastxr::image::RgbaImage;

const DISPLAY: &str = "samples/display-hand-interaction.png";
const YELLOW: &str = "samples/background-yellow-wall.png";
const SKY: &str = "samples/background-blue-sky.png";

/// The tool with HOME and the XDG folders of its own (a scratch home per test process; the
/// cache kept across runs, for Mesa's shader cache): no test reads or writes the user's files.
fn command() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_contrastxr"));
    cmd.envs(own_folders());
    cmd
}

fn own_folders() -> [(&'static str, PathBuf); 5] {
    let home = scratch("home");
    [
        ("XDG_CONFIG_HOME", home.join("config")),
        ("XDG_DATA_HOME", home.join("data")),
        ("XDG_STATE_HOME", home.join("state")),
        (
            "XDG_CACHE_HOME",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-cache"),
        ),
        ("HOME", home),
    ]
}

fn contrastxr(args: &[&str]) -> Output {
    command()
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run contrastxr")
}

/// A path in this test binary's scratch folder, inside the target directory (never the
/// system's temporary folder, where each run would leave its files): emptied once per run,
/// before its first use.
fn scratch(name: &str) -> PathBuf {
    static EMPTIED: std::sync::Once = std::sync::Once::new();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli");
    EMPTIED.call_once(|| {
        let _ = std::fs::remove_dir_all(&dir);
    });
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn load(path: &Path) -> RgbaImage {
    RgbaImage::load_png(path).unwrap()
}

fn sample(path: &str) -> RgbaImage {
    load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(path))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("valid JSON")
}

/// `contrastxr enhance` on the sample scene (output x.png) with extra arguments.
fn enhance_with(extra: &[&str]) -> Output {
    let mut args = vec![
        "enhance",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "-o",
        "x.png",
    ];
    args.extend_from_slice(extra);
    contrastxr(&args)
}
#[test]
fn enhance_keeps_black_and_changes_content() {
    let out = scratch("enhanced.png");
    let o = contrastxr(&[
        "enhance",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "-o",
        out.to_str().unwrap(),
        "--engine",
        "cpu",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (display, enhanced) = (sample(DISPLAY), load(&out));
    assert_eq!(
        (enhanced.width, enhanced.height, enhanced.has_alpha),
        (640, 360, false)
    );
    let mut changed = 0;
    for (d, e) in display.pixels.iter().zip(&enhanced.pixels) {
        if d[..3] == [0, 0, 0] {
            assert_eq!(d, e, "black is transparent and must stay black");
        } else if d != e {
            changed += 1;
        }
    }
    assert!(changed > 10_000, "only {changed} pixels changed");
}

#[test]
fn lambda_e_zero_reproduces_the_display() {
    let out = scratch("identity.png");
    let o = contrastxr(&[
        "enhance",
        "--display",
        DISPLAY,
        "--background",
        SKY,
        "-o",
        out.to_str().unwrap(),
        "--engine",
        "cpu",
        "--lambda-e",
        "0",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(load(&out).pixels, sample(DISPLAY).pixels);
}

#[test]
fn rgba_alpha_passes_through() {
    let mut display = sample(DISPLAY);
    display.has_alpha = true;
    for (i, p) in display.pixels.iter_mut().enumerate() {
        p[3] = (i % 251) as u8;
    }
    let (input, out) = (scratch("rgba-in.png"), scratch("rgba-out.png"));
    display.save_png(&input).unwrap();
    let o = contrastxr(&[
        "enhance",
        "--display",
        input.to_str().unwrap(),
        "--background",
        YELLOW,
        "-o",
        out.to_str().unwrap(),
        "--engine",
        "cpu",
        "--no-blur",
        "--no-fov",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let enhanced = load(&out);
    assert!(enhanced.has_alpha);
    for (d, e) in display.pixels.iter().zip(&enhanced.pixels) {
        assert_eq!(d[3], e[3]);
        if d[3] == 0 {
            assert_eq!(d, e, "alpha 0 is transparent and must stay untouched");
        }
    }
}

fn check_metrics(m: &serde_json::Value, foreground: u64) {
    let fg = m["foreground_pixels"].as_u64().unwrap();
    let enhanced = m["enhanced_pixels"].as_u64().unwrap();
    assert_eq!(fg, foreground);
    assert!(enhanced <= fg);
    let percent = m["enhanced_percent"].as_f64().unwrap();
    assert!((percent - 100.0 * enhanced as f64 / fg as f64).abs() < 1e-9);
    for key in [
        "delta_e_out_display",
        "delta_e_bg_display",
        "delta_e_bg_out",
    ] {
        let s = &m[key];
        let (min, mean, max) = (
            s["min"].as_f64().unwrap(),
            s["mean"].as_f64().unwrap(),
            s["max"].as_f64().unwrap(),
        );
        assert!(0.0 <= min && min <= mean && mean <= max, "{key}: {s}");
    }
}

fn foreground_count(img: &RgbaImage) -> u64 {
    img.pixels
        .iter()
        .filter(|p| p[3] != 0 && p[..3] != [0, 0, 0])
        .count() as u64
}

#[test]
fn evaluate_reports_consistent_metrics_and_a_figure() {
    let (out, fig) = (scratch("eval-out.png"), scratch("eval-fig.png"));
    let o = contrastxr(&[
        "enhance",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "-o",
        out.to_str().unwrap(),
        "--engine",
        "cpu",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = contrastxr(&[
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "--enhanced",
        out.to_str().unwrap(),
        "--json",
        "--figure",
        fig.to_str().unwrap(),
    ]);
    let m = json(&o);
    check_metrics(&m, foreground_count(&sample(DISPLAY)));
    // White content on a yellow wall is the paper's showcase: most pixels gain contrast.
    assert!(m["enhanced_percent"].as_f64().unwrap() > 50.0, "{m}");
    let figure = load(&fig);
    assert!(figure.width >= 3 * 640 && figure.height >= 360);
}

#[test]
fn evaluate_of_unchanged_output_finds_nothing_enhanced() {
    let o = contrastxr(&[
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        SKY,
        "--enhanced",
        DISPLAY,
        "--json",
    ]);
    let m = json(&o);
    assert_eq!(m["enhanced_pixels"], 0);
    assert_eq!(m["delta_e_out_display"]["max"], 0.0);
    // Nothing changed: the perceived contrast neither.
    assert_eq!(
        m["perceived_contrast_before"],
        m["perceived_contrast_after"]
    );
    assert_eq!(m["perceived_contrast_gain"], 1.0);
    assert_eq!(m["brought_to_target_fraction"], 0.0);
}

/// The perceived contrast `evaluate` reports, by hand from the model's second worked example
/// (docs/algorithm.md, *The perceptual method*: grey 0.5 over a grey 0.8 world at 5000 cd/m^2,
/// lens 0.3, 2 cpd has c 0.04 and C 4.298, so C / c = 107.45 there, which hardly moves with a
/// few cd/m^2). Grey on grey, c is the Michelson contrast `Y_D / (Y_D + 2 Y_tB)` and c' =
/// `c (1 - 1 / (107.45 c))`. Background code 231 is linear 0.799103, Y_tB = 0.3 * 5000 *
/// 0.799103 = 1198.654; display code 188 (linear 0.502886, Y_D 100.577): c 0.040265, c'
/// 0.030958, below the target 0.05; white (Y_D 200): c 0.077003, c' 0.067696.
#[test]
fn evaluate_reports_the_perceived_contrast_of_a_hand_computed_case() {
    let (display, output, background) = (
        scratch("pc-display.png"),
        scratch("pc-output.png"),
        scratch("pc-background.png"),
    );
    let grey = [188, 188, 188, 255];
    RgbaImage::new(2, 1, grey).save_png(&display).unwrap();
    let mut out = RgbaImage::new(2, 1, grey);
    out.set(1, 0, [255, 255, 255, 255]);
    out.save_png(&output).unwrap();
    RgbaImage::new(2, 1, [231, 231, 231, 255])
        .save_png(&background)
        .unwrap();
    let o = contrastxr(&[
        "evaluate",
        "--display",
        display.to_str().unwrap(),
        "--background",
        background.to_str().unwrap(),
        "--enhanced",
        output.to_str().unwrap(),
        "--no-blur",
        "--no-fov",
        "--transmittance",
        "0.3",
        "--world-nits",
        "5000",
        "--frequency",
        "2",
        "--json",
    ]);
    let m = json(&o);
    let f = |k: &str| m[k].as_f64().unwrap_or_else(|| panic!("{k} in {m}"));
    let near = |a: f64, b: f64, rel: f64| (a - b).abs() <= rel * b.abs();
    assert!(near(f("perceived_contrast_before"), 0.030958, 1e-3), "{m}");
    let after = (0.030958 + 0.067696) / 2.0;
    assert!(near(f("perceived_contrast_after"), after, 2e-3), "{m}");
    assert!(near(
        f("perceived_contrast_gain"),
        f("perceived_contrast_after") / f("perceived_contrast_before"),
        1e-12
    ));
    assert!(near(
        f("perceived_contrast_log2_gain"),
        f("perceived_contrast_gain").log2(),
        1e-12
    ));
    assert_eq!(
        [
            "left_alone_fraction",
            "brought_to_target_fraction",
            "out_of_reach_fraction"
        ]
        .map(f),
        [0.0, 0.5, 0.5],
        "{m}"
    );
    assert!(near(f("mean_world_luminance"), 1198.654, 1e-5), "{m}");
    assert_eq!(m["frequency"], "2");
    assert_eq!(m["frequency_cpd"], serde_json::json!([2.0]));
    assert_eq!(f("target_contrast"), 0.05);
    // The default frequency follows the blur: sigma 1.5 camera px, here one display px each,
    // at --ppd 15: 0.1 deg, so sqrt(ln 2 / 2) / (pi 0.1) = 1.8739 cpd.
    let o = contrastxr(&[
        "evaluate",
        "--display",
        display.to_str().unwrap(),
        "--background",
        background.to_str().unwrap(),
        "--enhanced",
        output.to_str().unwrap(),
        "--no-fov",
        "--ppd",
        "15",
        "--json",
    ]);
    let m = json(&o);
    let cpd = m["frequency_cpd"][0].as_f64().unwrap();
    assert!((cpd - 1.87391).abs() < 1e-4, "{m}");
    assert_eq!(m["frequency"], "blur");
}

/// Any method's output gets the perceived contrast, and the text output says it.
#[test]
fn evaluate_reports_the_perceived_contrast_for_every_method() {
    for method in ["luminance", "subtraction"] {
        let args = [
            "evaluate",
            "--display",
            DISPLAY,
            "--background",
            SKY,
            "--engine",
            "cpu",
            "--method",
            method,
        ];
        let m = json(&contrastxr(&[&args[..], &["--json"]].concat()));
        let f = |k: &str| m[k].as_f64().unwrap_or_else(|| panic!("{k} in {m}"));
        assert!(f("perceived_contrast_before") > 0.0, "{method}: {m}");
        assert!(f("perceived_contrast_after") > 0.0, "{method}: {m}");
        let classes =
            f("left_alone_fraction") + f("brought_to_target_fraction") + f("out_of_reach_fraction");
        assert!((classes - 1.0).abs() < 1e-9, "{method}: {m}");
        let o = contrastxr(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("perceived contrast c'"), "{text}");
        assert!(text.contains("out of reach"), "{text}");
    }
}

/// `--compare` runs each method on the same inputs: one JSON row per method, the same c'
/// before, and at 500 cd/m² (an office) the perceptual method changes colours far less than the
/// paper's (docs/algorithm.md, Measured on the samples); its figure has a row per method.
#[test]
fn evaluate_compares_methods_row_by_row_with_a_figure() {
    let figure = scratch("compare.png");
    let args = [
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        SKY,
        "--compare",
        "paper,perceptual",
        "--world-nits",
        "500",
        "--figure",
        figure.to_str().unwrap(),
    ];
    let rows = json(&contrastxr(&[&args[..], &["--json"]].concat()));
    let rows = rows.as_array().unwrap_or_else(|| panic!("{rows}"));
    let names: Vec<&str> = rows.iter().map(|r| r["method"].as_str().unwrap()).collect();
    assert_eq!(names, ["paper", "perceptual"]);
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} in {r}"));
    let (paper, perceptual) = (&rows[0], &rows[1]);
    assert_eq!(
        f(paper, "perceived_contrast_before"),
        f(perceptual, "perceived_contrast_before")
    );
    let change = |r: &serde_json::Value| r["delta_e_out_display"]["mean"].as_f64().unwrap();
    assert!(
        change(perceptual) < 0.7 * change(paper),
        "{perceptual} against {paper}"
    );
    let img = load(&figure);
    let single = scratch("single.png");
    let one = contrastxr(&[
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        SKY,
        "--compare",
        "perceptual",
        "--figure",
        single.to_str().unwrap(),
    ]);
    assert!(one.status.success(), "{}", stderr(&one));
    let text = String::from_utf8_lossy(&one.stdout);
    assert!(
        text.contains("perceptual") && text.contains("at target"),
        "{text}"
    );
    let row = load(&single);
    assert_eq!(img.width, row.width);
    assert!(
        img.height > 2 * row.height - 100,
        "{} vs {}",
        img.height,
        row.height
    );
    let o = contrastxr(&[&args[..6], &["paper,sharpest"]].concat());
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("'sharpest' is not a method"),
        "{}",
        stderr(&o)
    );
}

/// `enhance` prints the perceived contrast of its output at its `--ppd`: what `evaluate` says
/// of the same output at the same `--ppd`, with the frequency the blur halves there (sigma
/// 1.5 camera px, 640 display px over 0.65 of the 960 px wall: 1.025641 display px each; at
/// 10 px per degree 0.153846 deg, so 0.18739 / 0.153846 = 1.2180 cpd).
#[test]
fn enhance_reports_the_perceived_contrast_at_its_ppd() {
    let out = scratch("enhanced-ppd.png");
    let out = out.to_str().unwrap();
    let o = contrastxr(&[
        "enhance",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "-o",
        out,
        "--engine",
        "cpu",
        "--ppd",
        "10",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let said = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(said.contains("frequency blur: 1.22 cpd"), "{said}");
    let o = contrastxr(&[
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "--enhanced",
        out,
        "--ppd",
        "10",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let evaluated = String::from_utf8_lossy(&o.stdout).into_owned();
    let perceived = &evaluated[evaluated.find("perceived contrast c'").unwrap()..];
    assert!(
        said.ends_with(perceived),
        "enhance: {said}\nevaluate: {perceived}"
    );
    let o = enhance_with(&["--engine", "cpu", "--ppd", "0"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--ppd must be a number of pixels per degree > 0"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn evaluate_refuses_perceptual_settings_out_of_range() {
    for (flag, value, says) in [
        (
            "--min-luminance",
            "0.01",
            "min_luminance must be in [0.1, 31623]",
        ),
        ("--display-peak-nits", "0", "display_peak_nits must be > 0"),
        (
            "--target-contrast",
            "0",
            "target_contrast must be in (0, 1]",
        ),
        ("--frequency", "sharp", "--frequency"),
        (
            "--ppd",
            "0",
            "--ppd must be a number of pixels per degree > 0",
        ),
    ] {
        let o = contrastxr(&[
            "evaluate",
            "--display",
            DISPLAY,
            "--background",
            SKY,
            "--enhanced",
            DISPLAY,
            flag,
            value,
        ]);
        assert_eq!(o.status.code(), Some(1), "{flag} {value}");
        assert!(stderr(&o).contains(says), "{flag} {value}: {}", stderr(&o));
    }
}

#[test]
fn sweep_prints_one_row_per_lambda_and_a_figure() {
    let fig = scratch("sweep.png");
    let args = [
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        SKY,
        "--engine",
        "cpu",
        "--sweep",
        "0.2,0.6",
    ];
    let o = contrastxr(&[&args[..], &["--json"]].concat());
    let rows = json(&o);
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    let fg = foreground_count(&sample(DISPLAY));
    for (row, lambda) in rows.iter().zip([0.2, 0.6]) {
        assert!((row["lambda_e"].as_f64().unwrap() - lambda).abs() < 1e-6);
        check_metrics(row, fg);
    }
    let mean = |i: usize| rows[i]["delta_e_out_display"]["mean"].as_f64().unwrap();
    assert!(mean(1) > mean(0), "a larger lambda_e changes colours more");
    let o = contrastxr(&[&args[..], &["--figure", fig.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("lambda_e") && table.lines().count() == 3,
        "{table}"
    );
    let single_row = 360 + 2 * 16;
    assert!(load(&fig).height > 2 * 360 && load(&fig).height > single_row);
}

#[test]
fn missing_file_is_one_clear_sentence() {
    let o = contrastxr(&[
        "enhance",
        "--display",
        "nope.png",
        "--background",
        YELLOW,
        "-o",
        "x.png",
        "--engine",
        "cpu",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("cannot read the display image") && e.contains("nope.png"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
}

#[test]
fn non_png_is_reported() {
    let o = contrastxr(&[
        "evaluate",
        "--display",
        DISPLAY,
        "--background",
        "Cargo.toml",
        "--engine",
        "cpu",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("background image") && e.contains("not a readable PNG"),
        "{e}"
    );
}

#[test]
fn usage_errors_exit_2_and_bad_values_exit_1() {
    let o = contrastxr(&["enhance", "--background", YELLOW, "-o", "x.png"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--display is required"));
    let o = enhance_with(&["--colour", "red"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("unknown option --colour"));
    assert_eq!(contrastxr(&["frobnicate"]).status.code(), Some(2));
    let o = enhance_with(&["--lambda-e", "lots"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--lambda-e must be a number"));
    let o = enhance_with(&["--method", "magic"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("paper, hue-only"));
    let o = enhance_with(&["--blur-size", "4"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(contrastxr(&["--help"]).status.success());
    let help = contrastxr(&["evaluate", "--help"]);
    assert!(String::from_utf8_lossy(&help.stdout).contains("--sweep"));
}

/// The enhancement against a JPEG of the background (written by an independent encoder) is
/// the enhancement against the PNG within a small tolerance: the JPEG was read, not refused.
#[test]
fn jpeg_background_is_accepted() {
    let sky = sample(SKY);
    let rgb: Vec<u8> = sky.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    let jpeg = scratch("sky.jpg");
    jpeg_encoder::Encoder::new_file(&jpeg, 95)
        .unwrap()
        .encode(
            &rgb,
            sky.width as u16,
            sky.height as u16,
            jpeg_encoder::ColorType::Rgb,
        )
        .unwrap();
    let run = |background: &str, out: &Path| {
        let o = contrastxr(&[
            "enhance",
            "--display",
            DISPLAY,
            "--background",
            background,
            "-o",
            out.to_str().unwrap(),
            "--engine",
            "cpu",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        load(out)
    };
    let (from_png, from_jpeg) = (
        run(SKY, &scratch("sky-png.png")),
        run(jpeg.to_str().unwrap(), &scratch("sky-jpeg.png")),
    );
    let diffs: Vec<u8> = from_png
        .pixels
        .iter()
        .zip(&from_jpeg.pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| a[c].abs_diff(b[c])))
        .collect();
    let mean = diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / diffs.len() as f64;
    assert!(mean < 1.0, "mean difference {mean}");
    // The enhancement did act on the JPEG background (not a pass-through).
    assert_ne!(from_jpeg.pixels, sample(DISPLAY).pixels);
}

#[test]
fn version_and_completions() {
    let o = contrastxr(&["--version"]);
    assert!(o.status.success());
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        format!("contrastxr {}", env!("CARGO_PKG_VERSION"))
    );
    for (shell, marker) in [
        ("bash", "complete -F"),
        ("zsh", "#compdef contrastxr"),
        ("fish", "complete -c contrastxr"),
    ] {
        let o = contrastxr(&["completions", shell]);
        assert!(o.status.success(), "{}", stderr(&o));
        let script = String::from_utf8_lossy(&o.stdout);
        assert!(script.contains(marker), "{shell}: {script}");
        // Every subcommand and a few options of theirs are in every script.
        for word in ["enhance", "set", "log", "lambda-e", "fov-offset"] {
            assert!(script.contains(word), "{shell} lacks {word}");
        }
    }
    let o = contrastxr(&["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn negative_values_reach_the_checks() {
    // An option's value may start with '-': parsed, then checked by the method's validation.
    let o = enhance_with(&["--engine", "cpu", "--lambda-e", "-0.1"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("lambda_e"), "{}", stderr(&o));
    let out = scratch("negative-offset.png");
    let o = contrastxr(&[
        "enhance",
        "--display",
        DISPLAY,
        "--background",
        YELLOW,
        "-o",
        out.to_str().unwrap(),
        "--engine",
        "cpu",
        "--fov-offset",
        "-0.1,0.2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // `set lambda_e -0.1` reaches the setting's range check (and writes nothing).
    let config = scratch("negative.toml");
    let _ = std::fs::remove_file(&config);
    let o = command()
        .args(["set", "lambda_e", "-0.1"])
        .env("CONTRASTXR_CONFIG", &config)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("lambda_e must be >= 0"),
        "{}",
        stderr(&o)
    );
    assert!(!config.exists());
    let o = command()
        .args(["set", "fov_offset=-0.1,0.2"])
        .env("CONTRASTXR_CONFIG", &config)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&config).unwrap();
    assert!(text.contains("fov_offset = [-0.1, 0.2]"), "{text}");
}

/// `install --user` copies the library to a stable place and the manifest names the copy, so
/// removing or rebuilding the original does not unload the layer; the tool goes beside the
/// copy; `uninstall` removes them all.
#[test]
fn install_user_copies_the_library_and_uninstall_removes_it() {
    let home = scratch("xdg-data");
    let _ = std::fs::remove_dir_all(&home);
    let original = scratch("built/libcontrastxr.so");
    std::fs::create_dir_all(original.parent().unwrap()).unwrap();
    std::fs::write(&original, b"\x7fELF stand-in for the built library").unwrap();
    let run = |args: &[&str]| {
        command()
            .args(args)
            .env("XDG_DATA_HOME", &home)
            .output()
            .unwrap()
    };
    let o = run(&["install", "--user", "--library", original.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let copy = home.join("contrastxr/libcontrastxr.so");
    let manifest = home.join("openxr/1/api_layers/implicit.d/contrastxr.json");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
    assert_eq!(v["api_layer"]["library_path"], copy.to_str().unwrap());
    assert_eq!(v["api_layer"]["enable_environment"], "CONTRASTXR");
    // The shipped device profiles lie beside the copy, where the layer looks for them.
    let profiles = home.join("contrastxr/devices.toml");
    let shipped =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("devices.toml"));
    assert_eq!(
        std::fs::read_to_string(&profiles).unwrap(),
        shipped.unwrap()
    );
    // The tool beside the copy (a stable `contrastxr gl-programs`): this very tool.
    let tool = home.join("contrastxr/contrastxr");
    assert_eq!(
        std::fs::read(&tool).unwrap(),
        std::fs::read(env!("CARGO_BIN_EXE_contrastxr")).unwrap()
    );
    let o = Command::new(&tool).arg("--version").output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // `cargo clean` removes the original: the installed copy stays as it was.
    std::fs::remove_file(&original).unwrap();
    assert_eq!(
        std::fs::read(&copy).unwrap(),
        b"\x7fELF stand-in for the built library"
    );
    let o = run(&["uninstall", "--user"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!manifest.exists() && !copy.exists() && !profiles.exists() && !tool.exists());
    let o = run(&["uninstall"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("was not installed"));
}

/// `contrastxr calibrate` driven line by line on stdin (not a terminal) against a config file.
fn calibrate(config: &Path, args: &[&str], stdin: &str) -> Output {
    use std::io::Write;
    let mut child = command()
        .arg("calibrate")
        .args(args)
        .env("CONTRASTXR_CONFIG", config)
        .env_remove("CONTRASTXR_MODE")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run contrastxr calibrate");
    let mut input = child.stdin.take().expect("stdin");
    input.write_all(stdin.as_bytes()).expect("write stdin");
    drop(input);
    child.wait_with_output().expect("calibrate ends")
}

fn effective(config: &Path, app: &str) -> contrastxr::config::Settings {
    let text = std::fs::read_to_string(config).expect("config");
    let source = contrastxr::config::Source {
        path: config,
        text: &text,
    };
    let r = contrastxr::config::resolve(app, Some(source), &contrastxr::config::Env::default());
    assert!(r.problems.is_empty(), "{:?}", r.problems);
    r.settings
}

#[test]
fn calibrate_saves_each_eyes_nudges_and_puts_the_mode_back() {
    let config = scratch("calibrate.toml");
    std::fs::write(&config, "# mine\nmode = \"split\"\nlambda_e = 0.5\n").unwrap();
    // Left eye: 2 steps right, 1 up, one step bigger; right eye: 1 step left at half the step,
    // then 1 step shorter.
    let o = calibrate(
        &config,
        &[],
        "right right\nup bigger\nsideways\nnext\nfiner left\nshorter\nnext\n",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("mode = \"background\""), "{out}");
    assert!(out.contains("unknown command \"sideways\""), "{out}");
    let text = std::fs::read_to_string(&config).unwrap();
    assert!(
        text.starts_with("# mine\nmode = \"split\"\nlambda_e = 0.5\n"),
        "{text}"
    );
    let r = effective(&config, "").registration;
    assert_eq!(r.eye_offset, [[0.01, -0.005], [-0.0025, 0.0]]);
    // 1 / (1 + 2 * 0.0025) = 0.995025, kept to 5 decimals.
    assert_eq!(r.eye_scale, [[1.01, 1.01], [1.0, 0.99502]]);
    // Cancelled: both eyes back as they were, and still no mode line added.
    let o = calibrate(&config, &["--step", "0.02"], "left\nnext\nup\nquit\n");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&config).unwrap(), text);
}

#[test]
fn calibrate_ends_with_the_cameras_latency() {
    let config = scratch("calibrate-latency.toml");
    std::fs::write(&config, "camera_latency_ms = 10\n").unwrap();
    // Both eyes untouched, then the latency: 3 steps up, 1 down at a doubled step (10 ms).
    let o = calibrate(&config, &[], "next\nnext\nup up up\ncoarser down\nnext\n");
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("camera_latency_ms = 15"), "{out}");
    assert_eq!(effective(&config, "").motion.camera_latency_ms, 15.0);
    // Cancelled in the latency step: the latency is put back.
    let o = calibrate(&config, &[], "next\nnext\nup up\nquit\n");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(effective(&config, "").motion.camera_latency_ms, 15.0);
}

#[test]
fn calibrate_writes_an_app_table_and_removes_the_mode_it_added() {
    let config = scratch("calibrate-app.toml");
    std::fs::write(&config, "lambda_e = 0.5\n").unwrap();
    let o = calibrate(&config, &["--app", "hello_xr"], "next\ndown\n");
    assert!(o.status.success(), "{}", stderr(&o));
    let s = effective(&config, "hello_xr");
    assert_eq!(s.registration.eye_offset, [[0.0, 0.0], [0.0, 0.005]]);
    assert_eq!(s.params.mode.name(), "enhance");
    assert_eq!(
        effective(&config, "other").registration.eye_offset[1],
        [0.0, 0.0]
    );
    let text = std::fs::read_to_string(&config).unwrap();
    assert!(!text.contains("mode"), "{text}");
    let o = calibrate(&config, &["--step", "3"], "");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

/// On a terminal calibrate reads single keys (raw mode: arrows, no Enter needed, no echo).
/// The terminal is a pseudo-terminal from util-linux's `script`, fed keys a moment apart.
#[test]
fn calibrate_takes_single_keys_on_a_terminal() {
    use std::io::Write;
    if Command::new("script").arg("--version").output().is_err() {
        eprintln!("skipped: no `script` (util-linux) to make a terminal");
        return;
    }
    let config = scratch("calibrate-tty.toml");
    std::fs::write(&config, "lambda_e = 0.5\n").unwrap();
    let mut child = Command::new("script")
        .envs(own_folders())
        .args([
            "-qec",
            &format!("{} calibrate", env!("CARGO_BIN_EXE_contrastxr")),
            "/dev/null",
        ])
        .env("CONTRASTXR_CONFIG", &config)
        .env_remove("CONTRASTXR_MODE")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("run script");
    let mut keys = child.stdin.take().expect("stdin");
    // Right arrow twice and ']' on the left eye, Enter, 's' (down) on the right eye, Enter,
    // Enter past the latency step.
    for k in ["", "\x1b[C", "\x1b[C", "]", "\r", "s", "\r", "\r"] {
        std::thread::sleep(std::time::Duration::from_millis(300));
        keys.write_all(k.as_bytes()).unwrap();
        keys.flush().unwrap();
    }
    let out = child.wait_with_output().expect("script ends");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(!text.contains("[C"), "keys are not echoed: {text}");
    let r = effective(&config, "").registration;
    assert_eq!(r.eye_offset, [[0.01, 0.0], [0.0, 0.005]], "{text}");
    assert_eq!(r.eye_scale, [[1.01, 1.0], [1.0, 1.0]], "{text}");
    assert!(!std::fs::read_to_string(&config).unwrap().contains("mode"));
}

#[test]
fn calibrate_with_device_starts_from_and_saves_to_the_headsets_table() {
    let config = scratch("calibrate-device.toml");
    std::fs::write(
        &config,
        "left_eye_offset = [0.5, 0.5]\n[device.\"HMD\"]\nleft_eye_offset = [0.1, 0]\n",
    )
    .unwrap();
    let o = calibrate(&config, &["--device", "HMD"], "right\nnext\n");
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&config).unwrap();
    assert_eq!(
        text,
        "left_eye_offset = [0.5, 0.5]\n[device.\"HMD\"]\nleft_eye_offset = [0.105, 0.0]\n"
    );
    let o = calibrate(&config, &["--device", "HMD", "--app", "x"], "");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// `contrastxr ARGS` with HOME, every XDG directory and the V4L2 device folder under `root`,
/// none of this process's OpenXR, contrastxr, pressure-vessel or XDG variables, and `env`.
/// (The loader's compiled-in /etc is the one search path this cannot move.)
fn isolated(root: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_contrastxr"));
    cmd.args(args);
    for (name, _) in std::env::vars_os() {
        let name = name.to_string_lossy().into_owned();
        let prefixes = ["CONTRASTXR", "XR_", "PRESSURE_VESSEL", "XDG_"];
        if prefixes.iter().any(|p| name.starts_with(p)) {
            cmd.env_remove(&name);
        }
    }
    cmd.env("HOME", root)
        .env("XDG_DATA_HOME", root.join("data"))
        .env("XDG_CONFIG_HOME", root.join("config"))
        .env("XDG_STATE_HOME", root.join("state"))
        .env("XDG_CACHE_HOME", root.join("cache"))
        .env("XDG_CONFIG_DIRS", root.join("etc-xdg"))
        .env("XDG_DATA_DIRS", root.join("share"))
        .env("CONTRASTXR_V4L2_DIR", root.join("dev"))
        .envs(env.iter().copied())
        .output()
        .expect("run contrastxr")
}

/// An empty folder for one test's home.
fn fresh_home(name: &str) -> PathBuf {
    let root = scratch(name);
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("dev")).unwrap();
    root
}

/// Writes the layer's log in `root`'s state folder, as the layer would have left it.
fn write_layer_log(root: &Path, text: &str) {
    let log = root.join("state/contrastxr/layer.log");
    std::fs::create_dir_all(log.parent().unwrap()).unwrap();
    std::fs::write(&log, text).unwrap();
}

/// A log whose last app ran on the system "Glasses" (a [device."Glasses"] table applied).
const GLASSES_LOG: &str = "2026-01-01T00:00:01.000Z [pid 9] layer loaded into /usr/bin/b\n\
     2026-01-01T00:00:01.100Z [pid 9] system \"Glasses\": settings in a [device.\"Glasses\"] config table apply to it\n";

/// `contrastxr doctor --json` in `root`: the process and its report.
fn doctor(root: &Path, env: &[(&str, &str)]) -> (Output, serde_json::Value) {
    let o = isolated(root, &["doctor", "--json"], env);
    let report = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("doctor --json printed no JSON ({e}): {}", stderr(&o)));
    (o, report)
}

fn finding<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["findings"]
        .as_array()
        .expect("a findings array")
        .iter()
        .find(|f| f["name"] == name)
        .unwrap_or_else(|| panic!("no {name} finding in {report}"))
}

fn text<'a>(f: &'a serde_json::Value, field: &str) -> &'a str {
    f[field]
        .as_str()
        .unwrap_or_else(|| panic!("{field} of {f} is not a string"))
}

/// Whether the one loader path the tests cannot redirect (/etc/openxr/1/api_layers) already
/// holds a manifest of the layer, which would make the manifest findings differ.
fn layer_in_sysconfdir() -> bool {
    let dir = Path::new("/etc/openxr/1/api_layers/implicit.d");
    let found = std::fs::read_dir(dir).into_iter().flatten().any(|e| {
        e.ok()
            .and_then(|e| std::fs::read_to_string(e.path()).ok())
            .is_some_and(|t| t.contains("XR_APILAYER_CONTRASTXR"))
    });
    if found {
        eprintln!("skipped: {} already names the layer", dir.display());
    }
    found
}

#[test]
fn doctor_without_a_manifest_reports_the_problem_and_its_fix() {
    if layer_in_sysconfdir() {
        return;
    }
    let root = fresh_home("doctor-none");
    let (o, report) = doctor(&root, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(report["ok"], false);
    let m = finding(&report, "manifest");
    assert_eq!(m["status"], "problem", "{m}");
    let user_dir = root.join("data/openxr/1/api_layers/implicit.d");
    assert!(
        text(m, "detail").contains(&user_dir.display().to_string()),
        "{m}"
    );
    // The fix names the tool as the user can run it: this build is not on PATH, and sudo's
    // PATH would not find it either.
    let exe = env!("CARGO_BIN_EXE_contrastxr");
    assert!(
        text(m, "fix").contains(&format!("`{exe} install --user`")),
        "{m}"
    );
    assert!(
        text(m, "fix").contains(&format!("`sudo {exe} install --system`")),
        "{m}"
    );
    assert_eq!(finding(&report, "library")["status"], "warn");
    // Every finding, in order; a fix exactly where the status is not ok.
    let findings = report["findings"].as_array().unwrap();
    let names: Vec<&str> = findings.iter().map(|f| text(f, "name")).collect();
    assert_eq!(
        names,
        [
            "manifest",
            "library",
            "runtime",
            "vulkan",
            "config",
            "camera",
            "camera-profile",
            "device-profile",
            "last-app",
            "gpu-time",
            "steam"
        ]
    );
    for f in findings {
        assert_eq!(f["fix"].is_null(), f["status"] == "ok", "{f}");
    }
    // No runtime and no camera (an empty device folder) are problems of their own.
    assert_eq!(finding(&report, "runtime")["status"], "problem");
    assert_eq!(finding(&report, "camera")["status"], "problem");
    // The screen says the same.
    let o = isolated(&root, &["doctor"], &[]);
    assert_eq!(o.status.code(), Some(1));
    let screen = String::from_utf8_lossy(&o.stdout);
    assert!(screen.contains("problem  manifest "), "{screen}");
    assert!(screen.contains("fix: install the layer"), "{screen}");
}

#[test]
fn doctor_after_install_names_the_manifest_and_loads_its_library() {
    if layer_in_sysconfdir() {
        return;
    }
    let root = fresh_home("doctor-installed");
    // The library built beside the tool, as a user installs it.
    let o = isolated(&root, &["install", "--user"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let manifest = root.join("data/openxr/1/api_layers/implicit.d/contrastxr.json");
    let library = root.join("data/contrastxr/libcontrastxr.so");
    let (_, report) = doctor(&root, &[]);
    let m = finding(&report, "manifest");
    assert_eq!(m["status"], "ok", "{m}");
    assert!(m["fix"].is_null());
    let detail = text(m, "detail");
    assert!(
        detail.contains(&format!("implicit manifest {}", manifest.display()))
            && detail.contains(&format!("names {}", library.display())),
        "{detail}"
    );
    let l = finding(&report, "library");
    assert_eq!(l["status"], "ok", "{l}");
    assert_eq!(
        text(l, "detail"),
        format!(
            "{} loads and exports xrNegotiateLoaderApiLayerInterface",
            library.display()
        )
    );
    // No finding about a tool beside the library: the layer starts no process.
    assert!(
        !report["findings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["name"] == "opengl-builder"),
        "{report}"
    );
    // `doctor --help` lists every finding the report has.
    let help = String::from_utf8_lossy(&contrastxr(&["doctor", "--help"]).stdout).into_owned();
    for f in report["findings"].as_array().unwrap() {
        let name = text(f, "name");
        assert!(help.contains(&format!("  {name}  ")), "{name}: {help}");
    }
    // A second implicit manifest (a system-wide install) would load the layer twice.
    let system = root.join("share/openxr/1/api_layers/implicit.d");
    std::fs::create_dir_all(&system).unwrap();
    std::fs::copy(&manifest, system.join("contrastxr.json")).unwrap();
    let (_, report) = doctor(&root, &[]);
    let m = finding(&report, "manifest");
    assert_eq!(m["status"], "warn", "{m}");
    assert!(text(m, "detail").starts_with("2 implicit manifests"), "{m}");
    std::fs::remove_dir_all(root.join("share")).unwrap();
    // A file that is no loadable library: the manifest is fine, the library a problem.
    let standin = root.join("built/libcontrastxr.so");
    std::fs::create_dir_all(standin.parent().unwrap()).unwrap();
    std::fs::write(&standin, b"\x7fELF stand-in for the built library").unwrap();
    let o = isolated(
        &root,
        &["install", "--user", "--library", standin.to_str().unwrap()],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (o, report) = doctor(&root, &[]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(finding(&report, "manifest")["status"], "ok");
    let l = finding(&report, "library");
    assert_eq!(l["status"], "problem", "{l}");
    assert!(
        text(l, "detail").starts_with(&format!("{} cannot be loaded: ", library.display())),
        "{l}"
    );
    assert!(text(l, "fix").contains("contrastxr install --user"), "{l}");
}

#[test]
fn doctor_names_the_config_files_bad_line() {
    let root = fresh_home("doctor-config");
    let file = root.join("config/contrastxr/config.toml");
    std::fs::create_dir_all(file.parent().unwrap()).unwrap();
    std::fs::write(
        &file,
        "lambda_e = 0.5\n\n[app.\"hello_xr\"]\nlamda_e = 0.6\n",
    )
    .unwrap();
    let (o, report) = doctor(&root, &[]);
    assert_eq!(o.status.code(), Some(1));
    let c = finding(&report, "config");
    assert_eq!(c["status"], "problem", "{c}");
    assert_eq!(
        text(c, "detail"),
        format!(
            "1 problem(s): config {}:4: unknown key \"lamda_e\"",
            file.display()
        )
    );
    assert_eq!(
        text(c, "fix"),
        format!(
            "edit {} line 4; `contrastxr config check` lists every problem",
            file.display()
        )
    );
    std::fs::write(&file, "lambda_e = 0.5\n").unwrap();
    let (_, report) = doctor(&root, &[]);
    let c = finding(&report, "config");
    assert_eq!(c["status"], "ok", "{c}");
    assert_eq!(
        text(c, "detail"),
        format!("{}: no problems", file.display())
    );
}

/// An app whose session was OpenGL: doctor names the API from the log and says which one the
/// layer enhances, and the GPU time per frame the log gave last.
#[test]
fn doctor_names_the_last_sessions_graphics_api() {
    let root = fresh_home("doctor-opengl");
    write_layer_log(
        &root,
        "\
2026-01-01T00:00:00.000Z [pid 7] layer loaded into /usr/bin/blender
2026-01-01T00:00:00.300Z [pid 7] session is not a Vulkan session (OpenGL (Xlib)): contrastxr enhances Vulkan sessions only; passing its frames through untouched
",
    );
    let (_, report) = doctor(&root, &[]);
    let g = finding(&report, "gpu-time");
    assert_eq!(g["status"], "ok", "{g}");
    assert!(text(g, "detail").contains("logged no GPU time"), "{g}");
    let l = finding(&report, "last-app");
    assert_eq!(l["status"], "warn", "{l}");
    assert!(text(l, "detail").contains("(OpenGL (Xlib))"), "{l}");
    assert!(text(l, "fix").contains("Vulkan"), "{l}");
    assert_eq!(
        report["graphics_apis_enhanced"],
        serde_json::json!(["Vulkan", "OpenGL"])
    );
    // The layer's graphics-API line: the finding names the session's API.
    write_layer_log(
        &root,
        "\
2026-01-01T00:00:00.000Z [pid 8] layer loaded into /usr/bin/hello_xr
2026-01-01T00:00:00.300Z [pid 8] graphics API of this session: OpenGL (Xlib), enhanced
2026-01-01T00:00:00.900Z [pid 8] enhancement began 0.600 s after the session started
2026-01-01T00:01:01.000Z [pid 8] GPU time of the layer's work per frame over the last 60 s: median 0.412 ms, 95th percentile 0.530 ms, largest 1.203 ms, 1200 frames
2026-01-01T00:01:30.000Z [pid 8] GPU time of the layer's work per frame over the session: median 0.415 ms, 95th percentile 0.540 ms, largest 1.203 ms, 1800 frames
",
    );
    let (_, report) = doctor(&root, &[]);
    // The GPU time: the log's last such line, the session's.
    let g = finding(&report, "gpu-time");
    assert_eq!(g["status"], "ok", "{g}");
    assert_eq!(
        text(g, "detail"),
        "last app: GPU time of the layer's work per frame over the session: median 0.415 ms, \
         95th percentile 0.540 ms, largest 1.203 ms, 1800 frames"
    );
    let l = finding(&report, "last-app");
    assert_eq!(l["status"], "ok", "{l}");
    assert!(
        text(l, "detail").starts_with("last app /usr/bin/hello_xr (pid 8, ")
            && text(l, "detail").contains("), OpenGL (Xlib) session, enhanced: enhancement began"),
        "{l}"
    );
}

#[test]
fn doctor_reads_the_last_apps_log_and_the_headsets_profile() {
    let root = fresh_home("doctor-log");
    write_layer_log(
        &root,
        "\
2026-01-01T00:00:00.000Z [pid 7] layer loaded into /usr/bin/a
2026-01-01T00:00:00.500Z [pid 7] enhancement began 0.200 s after the session started
2026-01-01T00:00:01.000Z [pid 9] layer loaded into /usr/bin/b
2026-01-01T00:00:01.100Z [pid 9] system \"Glasses\": settings in a [device.\"Glasses\"] config table apply to it
2026-01-01T00:00:01.200Z [pid 9] environment blend mode OPAQUE is not ADDITIVE: passing frames through (see-through glasses whose runtime says opaque: set environment_blend_mode = \"additive\")
",
    );
    let config = root.join("config/contrastxr/config.toml");
    std::fs::create_dir_all(config.parent().unwrap()).unwrap();
    std::fs::write(&config, "background = \"color:#808080\"\n").unwrap();
    let (_, report) = doctor(&root, &[]);
    let l = finding(&report, "last-app");
    assert_eq!(l["status"], "warn", "{l}");
    assert!(
        text(l, "detail").starts_with("last app /usr/bin/b (pid 9, ")
            && text(l, "detail").contains("blend mode OPAQUE is not ADDITIVE"),
        "{l}"
    );
    assert!(text(l, "fix").contains("force = true"), "{l}");
    let p = finding(&report, "camera-profile");
    assert_eq!(p["status"], "warn", "{p}");
    assert!(text(p, "fix").contains("[device.\"Glasses\"]"), "{p}");
    assert_eq!(finding(&report, "camera")["status"], "ok");
    // The headset described: its profile is found.
    std::fs::write(
        &config,
        "background = \"color:#808080\"\n[device.\"Glasses\"]\ncamera_fov = [90.0, 60.0]\n",
    )
    .unwrap();
    let (_, report) = doctor(&root, &[]);
    let p = finding(&report, "camera-profile");
    assert_eq!(p["status"], "ok", "{p}");
    assert!(text(p, "detail").contains("[device.\"Glasses\"]"), "{p}");
    // The shipped profiles: none for this headset, then one that names it.
    let d = finding(&report, "device-profile");
    if !profiles_installed_here() {
        assert_eq!(d["status"], "warn", "{d}");
        let searched = format!(
            "no device profiles found (searched {}, /usr/local/lib/contrastxr/devices.toml, \
             /usr/share/contrastxr/devices.toml)",
            root.join("data/contrastxr/devices.toml").display()
        );
        assert_eq!(text(d, "detail"), searched, "{d}");
        assert!(text(d, "fix").contains("install --user"), "{d}");
    }
    let shipped = root.join("devices.toml");
    std::fs::write(
        &shipped,
        "[device.\"Glasses\"]\nenvironment_blend_mode = \"additive\"\n",
    )
    .unwrap();
    let shipped_text = shipped.to_string_lossy().into_owned();
    let (_, report) = doctor(&root, &[("CONTRASTXR_DEVICES", &shipped_text)]);
    let d = finding(&report, "device-profile");
    let wanted = format!("the headset \"Glasses\" matched the shipped profile [device.\"Glasses\"] in {shipped_text}");
    assert_eq!(text(d, "detail"), wanted, "{d}");
    // Shipped profiles for other headsets only: none matched.
    std::fs::write(
        &shipped,
        "[device.\"Other Glasses\"]\ncolour_camera = false\n",
    )
    .unwrap();
    let (_, report) = doctor(&root, &[("CONTRASTXR_DEVICES", &shipped_text)]);
    let d = finding(&report, "device-profile");
    assert_eq!(d["status"], "ok", "{d}");
    let wanted = format!("no shipped profile for \"Glasses\" in {shipped_text}: your own [device.\"Glasses\"] table describes it");
    assert_eq!(text(d, "detail"), wanted, "{d}");
    // Steam installed: its games need the variable, in their launch options or here.
    assert_eq!(finding(&report, "steam")["status"], "ok");
    const OPTIONS: &str = "PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS=1 CONTRASTXR=1 %command%";
    std::fs::create_dir_all(root.join(".steam/steam")).unwrap();
    let (_, report) = doctor(&root, &[]);
    // No game asks for the layer, and doctor cannot know whether one should: a note.
    let s = finding(&report, "steam");
    assert_eq!(s["status"], "ok", "{s}");
    assert!(text(s, "detail").contains(OPTIONS), "{s}");
    // A game started with the layer but without the import: a warning, whose fix ends it.
    let vdf = root.join(".steam/steam/userdata/123/config/localconfig.vdf");
    std::fs::create_dir_all(vdf.parent().unwrap()).unwrap();
    // Steam's layout of the file, on fewer lines.
    let game = |options: &str| {
        format!(
            "\"UserLocalConfigStore\" {{ \"Software\" {{ \"Valve\" {{ \"Steam\" {{ \"apps\" {{\n\
             \t\"620\" {{ \"LaunchOptions\" \"{options}\" }}\n}} }} }} }} }}\n"
        )
    };
    std::fs::write(&vdf, game("CONTRASTXR=1 %command%")).unwrap();
    let (_, report) = doctor(&root, &[]);
    let s = finding(&report, "steam");
    assert_eq!(s["status"], "warn", "{s}");
    assert!(text(s, "detail").contains("620"), "{s}");
    assert!(text(s, "fix").contains(OPTIONS), "{s}");
    // Launch options set per game, as steam-flatpak.md says: no warning.
    std::fs::write(&vdf, game(OPTIONS)).unwrap();
    let (_, report) = doctor(&root, &[]);
    let s = finding(&report, "steam");
    assert_eq!(s["status"], "ok", "{s}");
    assert!(text(s, "detail").contains("game(s) 620 import"), "{s}");
    let (_, report) = doctor(&root, &[("PRESSURE_VESSEL_IMPORT_OPENXR_1_LAYERS", "1")]);
    assert_eq!(finding(&report, "steam")["status"], "ok");
}

/// Vulkan with only a software device on a machine without a GPU: the finding says there is
/// no GPU device, and does not send the user to install the package that supplies the
/// software one.
#[test]
fn doctor_says_when_there_is_no_gpu_device() {
    let root = fresh_home("doctor-no-gpu");
    std::fs::create_dir_all(root.join("sys/class")).unwrap();
    let sys = root.join("sys").to_string_lossy().into_owned();
    let (_, report) = doctor(&root, &[("CONTRASTXR_SYSFS_ROOT", &sys)]);
    let v = finding(&report, "vulkan");
    if v["status"] != "warn" {
        eprintln!("skipped: this machine's Vulkan has a GPU device or none: {v}");
        return;
    }
    assert!(text(v, "detail").contains("no GPU device"), "{v}");
    assert!(!text(v, "fix").contains("mesa-vulkan-drivers"), "{v}");
    // A GPU the kernel drives whose device node this user lacks (a container): that is said.
    let card = root.join("sys/class/drm/renderD200");
    std::fs::create_dir_all(card.join("device")).unwrap();
    std::os::unix::fs::symlink(
        "../../../bus/pci/drivers/amdgpu",
        card.join("device/driver"),
    )
    .unwrap();
    let (_, report) = doctor(&root, &[("CONTRASTXR_SYSFS_ROOT", &sys)]);
    let v = finding(&report, "vulkan");
    assert!(
        text(v, "fix").contains("/dev/dri/renderD200 is missing"),
        "{v}"
    );
}

/// After `install --user`, `config print --device` applies the shipped profile of that system,
/// each value with its origin (the shipped file and line), and the user's device table beats it.
#[test]
fn config_print_device_shows_the_shipped_profile_below_the_users_table() {
    let root = fresh_home("shipped-profiles");
    let system = "Monado: Xreal Air Glasses";
    let o = isolated(&root, &["install", "--user"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let shipped = root.join("data/contrastxr/devices.toml");
    let line = std::fs::read_to_string(&shipped)
        .unwrap()
        .lines()
        .position(|l| l == format!("[device.\"{system}\"]"))
        .unwrap()
        + 2;
    let print = |root: &Path| {
        let o = isolated(root, &["config", "print", "--device", system], &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let out = print(&root);
    let wanted = format!(
        "environment_blend_mode = \"additive\"  # {} [device.\"{system}\"]:{line}",
        shipped.display()
    );
    assert!(out.contains(&wanted), "{wanted:?} not in\n{out}");
    // Another system: the default.
    let o = isolated(&root, &["config", "print", "--device", "Other"], &[]);
    let other = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        other.contains("environment_blend_mode = \"\"  # default"),
        "{other}"
    );
    // The user's device table overrides the shipped one.
    let config = root.join("config/contrastxr/config.toml");
    std::fs::create_dir_all(config.parent().unwrap()).unwrap();
    let text = format!("[device.\"{system}\"]\nenvironment_blend_mode = \"\"\n");
    std::fs::write(&config, text).unwrap();
    let out = print(&root);
    let wanted = format!(
        "environment_blend_mode = \"\"  # {} [device.\"{system}\"]:2",
        config.display()
    );
    assert!(out.contains(&wanted), "{wanted:?} not in\n{out}");
}

/// `config print --app NAME --device SYSTEM`: each value names the file and the table it came
/// from, or its variable, or the default; the app's table beats the device's, the environment
/// beats both.
#[test]
fn config_print_names_the_table_each_value_came_from() {
    let root = fresh_home("config-print-tables");
    let shipped = root.join("devices.toml");
    std::fs::write(
        &shipped,
        "[device.\"Glasses\"]\nlambda_e = 0.3\nblur_sigma = 2.5\nscene_distance = 4\n",
    )
    .unwrap();
    let config = root.join("config/contrastxr/config.toml");
    std::fs::create_dir_all(config.parent().unwrap()).unwrap();
    std::fs::write(
        &config,
        "transmittance = 0.3\n[device.\"Glasses\"]\nlambda_e = 0.5\nblur_sigma = 3\n\
         [app.\"hello_xr\"]\nlambda_e = 0.6\n",
    )
    .unwrap();
    let shipped_text = shipped.to_string_lossy().into_owned();
    let args = [
        "config", "print", "--app", "hello_xr", "--device", "Glasses",
    ];
    let env = [
        ("CONTRASTXR_DEVICES", shipped_text.as_str()),
        ("CONTRASTXR_BLUR_SIGMA", "1.25"),
    ];
    let o = isolated(&root, &args, &env);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let (c, s) = (config.display(), shipped.display());
    for wanted in [
        format!("lambda_e = 0.6  # {c} [app.\"hello_xr\"]:6"),
        format!("scene_distance = 4  # {s} [device.\"Glasses\"]:4"),
        format!("transmittance = 0.3  # {c}:1"),
        "blur_sigma = 1.25  # env CONTRASTXR_BLUR_SIGMA".to_string(),
        "blur_size = 3  # default".to_string(),
    ] {
        assert!(out.contains(&wanted), "{wanted:?} not in\n{out}");
    }
    // Another app: the user's device table, above the shipped one.
    let args = ["config", "print", "--app", "other", "--device", "Glasses"];
    let o = isolated(&root, &args, &env[..1]);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    for wanted in [
        format!("lambda_e = 0.5  # {c} [device.\"Glasses\"]:3"),
        format!("blur_sigma = 3  # {c} [device.\"Glasses\"]:4"),
    ] {
        assert!(out.contains(&wanted), "{wanted:?} not in\n{out}");
    }
}

/// Glasses whose shipped profile says they have no colour camera: with the default `v4l2:auto`
/// background and no camera connected, doctor suggests another kind of background instead of
/// reporting a missing camera; without that profile it reports the missing camera.
#[test]
fn doctor_suggests_another_background_for_glasses_without_a_colour_camera() {
    let root = fresh_home("doctor-no-colour-camera");
    write_layer_log(&root, GLASSES_LOG);
    let (_, report) = doctor(&root, &[]);
    let c = finding(&report, "camera");
    assert_eq!(c["status"], "problem", "{c}");
    let shipped = root.join("devices.toml");
    std::fs::write(&shipped, "[device.\"Glasses\"]\ncolour_camera = false\n").unwrap();
    let shipped_text = shipped.to_string_lossy().into_owned();
    let (_, report) = doctor(&root, &[("CONTRASTXR_DEVICES", &shipped_text)]);
    let c = finding(&report, "camera");
    assert_eq!(c["status"], "warn", "{c}");
    assert!(text(c, "detail").contains("no colour camera"), "{c}");
    assert!(text(c, "fix").contains("image:PATH"), "{c}");
}

/// One frame of an animated PNG: (delay numerator, denominator) and its RGB bytes.
type ApngFrame = ((u16, u16), Vec<u8>);

/// The size of an animated PNG and its frames.
fn apng_frames(path: &Path) -> ((u32, u32), Vec<ApngFrame>) {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let size = (reader.info().width, reader.info().height);
    let count = reader.info().animation_control.expect("an APNG").num_frames;
    let mut frames = Vec::new();
    for _ in 0..count {
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        let fc = reader.info().frame_control.unwrap();
        assert_eq!((fc.width, fc.height), size, "every frame is whole");
        frames.push(((fc.delay_num, fc.delay_den), buf));
    }
    (size, frames)
}

#[test]
fn pan_then_animate_writes_an_animation_of_the_captures() {
    let root = scratch("animate");
    let _ = std::fs::remove_dir_all(&root);
    let video = root.join("video");
    let o = contrastxr(&[
        "pan",
        YELLOW,
        SKY,
        "--frames",
        "6",
        "-o",
        video.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let frame = |i: usize| load(&video.join(format!("frame-{i:04}.png")));
    assert_eq!(std::fs::read_dir(&video).unwrap().count(), 6);
    assert_eq!((frame(0).width, frame(0).height), (960, 540));
    assert_eq!(
        frame(0).pixels,
        sample(YELLOW).pixels,
        "starts on the first image"
    );
    assert_ne!(frame(3).pixels, frame(0).pixels, "the window moves");
    // A second pan into the same folder would mix two videos: refused.
    let again = contrastxr(&["pan", YELLOW, SKY, "-o", video.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(1), "{}", stderr(&again));

    // Captures as the layer writes them, 50 ms apart, against frames of the pan.
    let captures = root.join("capture");
    std::fs::create_dir_all(&captures).unwrap();
    let display = sample(DISPLAY);
    for i in 0..4u64 {
        let stem = captures.join(format!("frame-{}-view-0", 10 + i));
        let file = |suffix: &str| PathBuf::from(format!("{}{suffix}", stem.display()));
        display.save_png(&file("-display.png")).unwrap();
        display.save_png(&file("-output.png")).unwrap();
        frame(i as usize)
            .save_png(&file("-background.png"))
            .unwrap();
        let json =
            serde_json::json!({"frame": 10 + i, "display_time": 1_000_000_000 + i * 50_000_000});
        std::fs::write(file(".json"), json.to_string()).unwrap();
    }
    let anim = root.join("animation.png");
    let o = contrastxr(&[
        "animate",
        "--captures",
        captures.to_str().unwrap(),
        "-o",
        anim.to_str().unwrap(),
        "--frames",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (size, frames) = apng_frames(&anim);
    // Five 320x180 panels (the 640x360 display halved) 12 apart, with a 16-pixel margin.
    assert_eq!(size, (5 * 320 + 4 * 12 + 2 * 16, 180 + 2 * 16));
    // Captures 10, 11 and 13: each shown until the next one's display time, the last for the
    // average.
    let delays: Vec<(u16, u16)> = frames.iter().map(|f| f.0).collect();
    assert_eq!(delays, [(50, 1000), (100, 1000), (75, 1000)]);
    assert_ne!(frames[0].1, frames[1].1, "the background moved");
    assert_ne!(frames[1].1, frames[2].1, "the background moved");
    let o = contrastxr(&[
        "animate",
        "--captures",
        video.to_str().unwrap(),
        "-o",
        "x.png",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no captures"), "{}", stderr(&o));
}

/// A profile that names the headset's camera by USB id: doctor says whether it is connected
/// (USB devices from a fake sysfs).
#[test]
fn doctor_says_whether_the_profiles_camera_is_connected() {
    let root = fresh_home("doctor-profile-camera");
    write_layer_log(&root, GLASSES_LOG);
    let shipped = root.join("devices.toml");
    std::fs::write(
        &shipped,
        "[device.\"Glasses\"]\ncamera_usb_ids = \"0c45:636b,0c45:6368\"\n",
    )
    .unwrap();
    let sys = root.join("sys");
    std::fs::create_dir_all(sys.join("class/video4linux")).unwrap();
    let env = [
        ("CONTRASTXR_DEVICES", shipped.to_str().unwrap()),
        ("CONTRASTXR_SYSFS_ROOT", sys.to_str().unwrap()),
    ];
    let (_, report) = doctor(&root, &env);
    let d = finding(&report, "device-profile");
    assert_eq!(d["status"], "warn", "{d}");
    let named = format!(
        "its camera, camera_usb_ids = \"0c45:636b,0c45:6368\" ({} [device.\"Glasses\"]:2), is not connected",
        shipped.display()
    );
    assert!(
        text(d, "detail").starts_with("the headset \"Glasses\" matched"),
        "{d}"
    );
    assert!(text(d, "detail").ends_with(&named), "{d}");
    assert!(text(d, "fix").contains("0c45:636b"), "{d}");
    // Its camera on USB as video3 (an interface of USB device 1-2), another camera as video1.
    for (node, port, product) in [("video1", 1, "0825"), ("video3", 2, "6368")] {
        let usb = sys.join(format!("devices/pci0000:00/usb1/1-{port}"));
        std::fs::create_dir_all(usb.join(format!("1-{port}:1.0"))).unwrap();
        std::fs::write(usb.join("idVendor"), "0c45\n").unwrap();
        std::fs::write(usb.join("idProduct"), format!("{product}\n")).unwrap();
        let class = sys.join("class/video4linux").join(node);
        std::fs::create_dir_all(&class).unwrap();
        std::os::unix::fs::symlink(usb.join(format!("1-{port}:1.0")), class.join("device"))
            .unwrap();
    }
    let (_, report) = doctor(&root, &env);
    let d = finding(&report, "device-profile");
    assert_eq!(d["status"], "ok", "{d}");
    let connected = format!(
        "is connected: {} (0c45:6368)",
        root.join("dev/video3").display()
    );
    assert!(text(d, "detail").ends_with(&connected), "{d}");
}

/// Shipped profiles installed on this machine (the package's or `install --system`'s), which
/// an isolated home cannot hide.
fn profiles_installed_here() -> bool {
    [
        "/usr/share/contrastxr/devices.toml",
        "/usr/local/lib/contrastxr/devices.toml",
    ]
    .iter()
    .any(|p| Path::new(p).exists())
}

/// `config path` with no config file names the one `set` would create, and exits 0.
#[test]
fn config_path_names_the_file_set_would_create() {
    let root = fresh_home("config-path");
    let user = root.join("config/contrastxr/config.toml");
    let o = isolated(&root, &["config", "path"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        format!("{}\n", user.display())
    );
    assert!(stderr(&o).contains("no config file yet"), "{}", stderr(&o));
    // Once it exists: the path alone.
    let o = isolated(&root, &["set", "lambda_e", "0.5"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = isolated(&root, &["config", "path"], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        format!("{}\n", user.display())
    );
    assert_eq!(stderr(&o), "");
}

/// `config print --device` says which device profiles file it read, or where it looked.
#[test]
fn config_print_device_names_the_profiles_file_or_the_folders_searched() {
    let root = fresh_home("config-print-profiles");
    let print = |env: &[(&str, &str)]| {
        let o = isolated(
            &root,
            &["config", "print", "--device", "Monado: Rokid Max"],
            env,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    if !profiles_installed_here() {
        let out = print(&[]);
        let searched = format!(
            "# device profiles: none found (searched {}, ",
            root.join("data/contrastxr/devices.toml").display()
        );
        assert!(out.contains(&searched), "{searched:?} not in\n{out}");
        assert!(
            out.contains("environment_blend_mode = \"\"  # default"),
            "{out}"
        );
    }
    let shipped = root.join("devices.toml");
    std::fs::write(&shipped, "[device.\"Monado: Rokid Max\"]\nlambda_e = 0.3\n").unwrap();
    let out = print(&[("CONTRASTXR_DEVICES", shipped.to_str().unwrap())]);
    let read = format!("# device profiles: {}\n", shipped.display());
    assert!(out.contains(&read), "{read:?} not in\n{out}");
    // Without --device no profile applies, and none is named.
    let o = isolated(&root, &["config", "print"], &[]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("# device profiles"));
}

/// A camera named by USB id in the user's settings is checked before any app has run.
#[test]
fn doctor_checks_the_usb_camera_of_the_settings_before_an_app_ran() {
    let root = fresh_home("doctor-usb-ids-no-app");
    let sys = root.join("sys");
    std::fs::create_dir_all(sys.join("class/video4linux")).unwrap();
    let env = [
        ("CONTRASTXR_CAMERA_USB_IDS", "0c45:636b"),
        ("CONTRASTXR_SYSFS_ROOT", sys.to_str().unwrap()),
    ];
    let (_, report) = doctor(&root, &env);
    let d = finding(&report, "device-profile");
    assert_eq!(d["status"], "warn", "{d}");
    let named = "its camera, camera_usb_ids = \"0c45:636b\" (env CONTRASTXR_CAMERA_USB_IDS), \
                 is not connected";
    assert!(text(d, "detail").ends_with(named), "{d}");
    assert!(text(d, "fix").contains("0c45:636b"), "{d}");
}

#[test]
fn completions_without_a_shell_names_every_shell() {
    let o = contrastxr(&["completions"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("bash, zsh, fish, elvish or powershell"),
        "{}",
        stderr(&o)
    );
    // The tool's command list names every shell a script is printed for.
    let help = String::from_utf8_lossy(&contrastxr(&["--help"]).stdout).into_owned();
    let line = help
        .lines()
        .find(|l| l.trim_start().starts_with("completions "))
        .unwrap_or_else(|| panic!("no completions line in {help}"));
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        assert!(
            contrastxr(&["completions", shell]).status.success(),
            "{shell}"
        );
        assert!(line.contains(shell), "{line}");
    }
}

/// The command list says what install and uninstall write and remove.
#[test]
fn install_and_uninstall_summaries_say_what_they_do() {
    let help = String::from_utf8_lossy(&contrastxr(&["--help"]).stdout).into_owned();
    let line = |name: &str| {
        help.lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("no {name} line in {help}"))
            .to_string()
    };
    assert!(line("install").contains("--system"), "{help}");
    let uninstall = line("uninstall");
    for part in ["manifest", "library", "tool"] {
        assert!(uninstall.contains(part), "{uninstall}");
    }
}

/// The help of the commands that run the method: the engine option indented like the others,
/// and the image formats they read.
#[test]
fn enhance_and_evaluate_help_line_up_every_option() {
    for command in ["enhance", "evaluate"] {
        let o = contrastxr(&[command, "--help"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let help = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(help.contains("\n  --engine E "), "{help}");
        assert!(help.contains("\n  --lambda-e F "), "{help}");
    }
    let help = String::from_utf8_lossy(&contrastxr(&["enhance", "--help"]).stdout).into_owned();
    assert!(help.contains("PNG or JPEG in, PNG out"), "{help}");
}

/// Doctor names documents where the reader has them: the package's installed copy, else this
/// build's checkout (never a bare `docs/...`, dead outside the source tree).
#[test]
fn doctor_names_documents_that_exist() {
    let root = fresh_home("doctor-docs");
    let (_, report) = doctor(&root, &[]);
    let steam = text(finding(&report, "steam"), "detail").to_string();
    let doc = steam
        .rsplit_once('(')
        .and_then(|(_, rest)| rest.strip_suffix(')'))
        .unwrap_or_else(|| panic!("no document named: {steam}"));
    assert!(doc.ends_with("steam-flatpak.md"), "{steam}");
    assert!(
        Path::new(doc).is_absolute() && Path::new(doc).is_file(),
        "{steam}"
    );
}
