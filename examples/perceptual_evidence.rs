//! Prints the table of docs/algorithm.md, *Measured on the samples* (run:
//! `cargo run --example perceptual_evidence`): the paper's method and the perceptual method,
//! both by their CPU references in f64 (the paper's `enhance_linear`, `perceptual_over_paper`),
//! on the bundled scenes (each display image of `samples/` over each background, placed as the
//! command line places them) at three world luminances, display 200 cd/m^2, lens 0.4, the
//! frequency the blur halves at 20 pixels per degree. Per world and method: the c' gain (mean
//! over the scenes, and its range), the share of content at the target c', the mean and
//! largest per-pixel CIELAB change; then the targets, each with whether it is met.

use std::path::Path;

use contrastxr::algorithm::perception::frame_report::{frame_report, FrameReport, ReportPixel};
use contrastxr::algorithm::perception::perceptual_pixel::perceptual_over_paper;
use contrastxr::algorithm::perceptual_settings::PerceptualSettings;
use contrastxr::algorithm::{enhance_linear, Params, Stored};
use contrastxr::background_preparation::prepare;
use contrastxr::colour;
use contrastxr::evaluate::perception_report::{model, offline_frequencies};
use contrastxr::image::RgbaImage;
use glam::DVec3;

const DISPLAYS: [&str; 2] = ["display-hand-interaction.png", "display-text-swatches.png"];
const BACKGROUNDS: [&str; 4] = [
    "background-yellow-wall.png",
    "background-blue-sky.png",
    "background-grey-office.png",
    "background-meadow.png",
];
const WORLDS: [f64; 3] = [20.0, 500.0, 5000.0];
const PPD: f64 = 20.0;
/// How far (CIE76) a change may exceed the paper's and still count as no more: the CIELAB
/// round trip's noise.
const SLACK: f64 = 1e-6;

struct Scene {
    name: String,
    display: Vec<(DVec3, f64)>,
    background: Vec<DVec3>,
    background_scaled: Vec<DVec3>,
    display_width: u32,
    camera_width: u32,
}

fn load(name: &str) -> RgbaImage {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name);
    RgbaImage::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn scenes(params: &Params) -> Vec<Scene> {
    let mut out = Vec::new();
    for d in DISPLAYS {
        let display = load(d);
        for b in BACKGROUNDS {
            let camera = load(b);
            let bg = prepare(&camera, display.width, display.height, params);
            out.push(Scene {
                name: format!(
                    "{} / {}",
                    d.trim_start_matches("display-").trim_end_matches(".png"),
                    b.trim_start_matches("background-").trim_end_matches(".png")
                ),
                display: display
                    .pixels
                    .iter()
                    .map(|p| {
                        let rgb = colour::srgb8_to_linear([p[0], p[1], p[2]]);
                        (rgb, f64::from(p[3]) / 255.0)
                    })
                    .collect(),
                background: bg.linear,
                background_scaled: bg.scaled,
                display_width: display.width,
                camera_width: camera.width,
            });
        }
    }
    out
}

/// One method on one scene: its frame report and the largest amount (CIE76) by which any
/// pixel's change exceeds the paper's (0 for the paper itself).
struct Run {
    report: FrameReport,
    beyond_paper: f64,
}

fn change(a: DVec3, b: DVec3) -> f64 {
    colour::delta_e(colour::linear_to_lab(a), colour::linear_to_lab(b))
}

fn run(scene: &Scene, params: &Params, perceptual: bool) -> Run {
    let frequencies = offline_frequencies(params, scene.display_width, scene.camera_width, PPD);
    let m = model(params, frequencies);
    let mut beyond_paper: f64 = 0.0;
    let pixels: Vec<ReportPixel> = scene
        .display
        .iter()
        .zip(&scene.background)
        .zip(&scene.background_scaled)
        .map(|((&(d, alpha), &b), &bs)| {
            let paper = enhance_linear(d, alpha, b, bs, params).unwrap_or(d);
            let output = if perceptual {
                let out = perceptual_over_paper(d, alpha, b, params, &m).output;
                beyond_paper = beyond_paper.max(change(d, out) - change(d, paper));
                out
            } else {
                paper
            };
            ReportPixel {
                display: d,
                alpha,
                background: b,
                output,
            }
        })
        .collect();
    Run {
        report: frame_report(pixels, &m),
        beyond_paper,
    }
}

/// A method at one world luminance and target, over every scene.
struct Row {
    gains: Vec<f64>,
    at_target: f64,
    mean_delta_e: f64,
    max_delta_e: f64,
    beyond_paper: f64,
}

fn row(scenes: &[Scene], params: &Params, perceptual: bool) -> Row {
    let runs: Vec<Run> = std::thread::scope(|s| {
        let handles: Vec<_> = scenes
            .iter()
            .map(|scene| s.spawn(move || run(scene, params, perceptual)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    // Shares and the mean change pooled over every content pixel of every scene.
    let n: f64 = runs.iter().map(|r| r.report.content_pixels as f64).sum();
    let pooled = |f: fn(&FrameReport) -> f64| {
        runs.iter()
            .map(|r| f(&r.report) * r.report.content_pixels as f64)
            .sum::<f64>()
            / n
    };
    Row {
        gains: runs.iter().map(|r| r.report.gain).collect(),
        at_target: pooled(|r| r.left_alone + r.brought_to_target),
        mean_delta_e: pooled(|r| r.mean_delta_e),
        max_delta_e: runs
            .iter()
            .map(|r| r.report.max_delta_e)
            .fold(0.0, f64::max),
        beyond_paper: runs.iter().map(|r| r.beyond_paper).fold(0.0, f64::max),
    }
}

fn params_at(world: f64, target: f64) -> Params {
    Params {
        perceptual: PerceptualSettings {
            display_peak_nits: 200.0,
            world_nits: world,
            target_contrast: target,
            ..PerceptualSettings::default()
        },
        transmittance: 0.4,
        // Outputs in linear light, not quantised: the methods themselves.
        stored: Stored::Exact,
        ..Params::default()
    }
}

fn print_row(label: &str, method: &str, r: &Row) {
    let mean = r.gains.iter().sum::<f64>() / r.gains.len() as f64;
    let (lo, hi) = r
        .gains
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &g| {
            (lo.min(g), hi.max(g))
        });
    println!(
        "| {label} | {method} | x{mean:.3} (x{lo:.3} to x{hi:.3}) | {:.1} % | {:.2} | {:.2} |",
        100.0 * r.at_target,
        r.mean_delta_e,
        r.max_delta_e
    );
}

fn met(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "NOT met"
    }
}

fn main() {
    let base = params_at(1000.0, 0.05);
    base.validate().expect("valid settings");
    let scenes = scenes(&base);
    let frequencies =
        offline_frequencies(&base, scenes[0].display_width, scenes[0].camera_width, PPD);
    println!(
        "{} scenes ({}), display 200 cd/m^2, lens 0.4, {:.3} cpd (blur at {PPD} ppd), CPU references in f64",
        scenes.len(),
        scenes
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        frequencies.cpd()[0]
    );
    println!();
    println!("| world, target c' | method | c' gain: mean (range) over scenes | content at target | mean ΔE | largest ΔE |");
    println!("|---|---|---|---|---|---|");
    let mut default_rows = Vec::new();
    for world in WORLDS {
        let params = params_at(world, 0.05);
        let paper = row(&scenes, &params, false);
        let perceptual = row(&scenes, &params, true);
        let label = format!("{world} cd/m², 0.05");
        print_row(&label, "paper", &paper);
        print_row(&label, "perceptual", &perceptual);
        default_rows.push((world, paper, perceptual));
    }
    let params = params_at(5000.0, 1.0);
    let paper_equal = row(&scenes, &params, false);
    let perceptual_equal = row(&scenes, &params, true);
    print_row("5000 cd/m², 1", "paper", &paper_equal);
    print_row("5000 cd/m², 1", "perceptual", &perceptual_equal);

    println!();
    let summed = |r: &Row| r.gains.iter().map(|g| g - 1.0).sum::<f64>();
    let (p, q) = (summed(&paper_equal), summed(&perceptual_equal));
    println!(
        "- Equal change (target 1), 5000 cd/m²: summed c' gain - 1 over the scenes {q:.4} (perceptual) vs {p:.4} (paper), {:.2}x: {} (target >= 2x); largest change beyond the paper's {:.2e} ΔE: {}",
        q / p,
        met(q >= 2.0 * p),
        perceptual_equal.beyond_paper,
        met(perceptual_equal.beyond_paper <= SLACK)
    );
    for (world, paper, perceptual) in &default_rows {
        let less = 1.0 - perceptual.mean_delta_e / paper.mean_delta_e;
        let needs_less = *world < 1000.0;
        println!(
            "- Default target, {world} cd/m²: mean ΔE {:.1} % less than the paper's{}; content at target {:.1} % vs {:.1} %: {}; largest change beyond the paper's {:.2e}: {}",
            100.0 * less,
            if needs_less {
                format!(": {} (target >= 30 %)", met(less >= 0.3))
            } else {
                String::new()
            },
            100.0 * perceptual.at_target,
            100.0 * paper.at_target,
            met(perceptual.at_target >= paper.at_target),
            perceptual.beyond_paper,
            met(perceptual.beyond_paper <= SLACK)
        );
    }
}
