//! `contrastxr evaluate`: the paper's enhanced-pixel metric and the perceived contrast before
//! and after, for one enhancement or a sweep over lambda_e; optionally a figure (perceived
//! original | perceived enhanced | cyan map).

use contrastxr::algorithm::{Method, Params};
use contrastxr::background_preparation;
use contrastxr::evaluate::class_figure::class_row;
use contrastxr::evaluate::perception_report::{model as perception_model, offline_frequencies};
use contrastxr::evaluate::{self as eval, Metrics, PerceptionReport};
use contrastxr::image::RgbaImage;

use super::args::parse_list;
use super::args::{Args, Opt};
use super::backend_choice::{self, Backend};
use super::error::CliError;
use super::options::{self, method_usage, ppd_usage, ENGINE_USAGE};

pub const OPTIONS: &[Opt] = &[
    Opt::value("--display", "D.png"),
    Opt::value("--background", "B.png"),
    Opt::value("--enhanced", "OUT.png"),
    Opt::value("--sweep", "L1,L2,..."),
    Opt::flag("--json"),
    Opt::value("--figure", "FIG.png"),
    Opt::flag("--app-images"),
    Opt::value("--compare", "M1,M2,..."),
];

const USAGE: &str = "\
usage: contrastxr evaluate --display D.png --background B.png [--enhanced OUT.png] [options]
       contrastxr evaluate --display D.png --background B.png --sweep 0.2,0.4,0.6,0.8,1.0 [options]
       contrastxr evaluate --display D.png --background B.png --compare paper,perceptual [options]

Measures the share of foreground pixels whose contrast with the background went up by a
noticeable amount (the paper's metric), and the perceived contrast c' of the content before
and after (the perceptual model, with its settings below). Without --enhanced the method runs
first (--engine).
  --enhanced OUT.png   the enhanced image to measure (the display's size)
  --sweep L1,L2,...    run the method at each lambda_e and print one row per value
  --json               print the metrics as JSON (an array of rows for --sweep)
  --figure FIG.png     write a figure; one row per lambda_e for --sweep
  --app-images         put the display and enhanced images themselves in the figure too
  --compare M1,M2,...  run each method and print one row per method; the figure has a row per
                       method: perceived original, perceived output, and the content pixels by
                       perceived contrast (left alone green, brought to the target cyan, out of
                       reach magenta)
";

pub fn usage() -> String {
    format!("{USAGE}{}\n{}{ENGINE_USAGE}", ppd_usage(), method_usage())
}

struct Inputs {
    display: RgbaImage,
    camera: RgbaImage,
    params: Params,
    engine: Backend,
    json: bool,
    figure: Option<String>,
    app_images: bool,
    ppd: f64,
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let display_path = args.required(&["--display"])?;
    let background_path = args.required(&["--background"])?;
    let enhanced = args.value(&["--enhanced"])?;
    let sweep = args.value(&["--sweep"])?;
    let json = args.flag("--json");
    let figure = args.value(&["--figure"])?;
    let app_images = args.flag("--app-images");
    let compare = args.value(&["--compare"])?;
    let ppd = options::pixels_per_degree(args)?;
    let params = options::params(args)?;
    let engine = options::engine(args)?;
    args.finish()?;
    if enhanced.is_some() && sweep.is_some() {
        return Err(CliError::Usage(
            "--sweep runs the method itself; leave out --enhanced".into(),
        ));
    }
    if compare.is_some() && (enhanced.is_some() || sweep.is_some()) {
        return Err(CliError::Usage(
            "--compare runs each method itself; leave out --enhanced and --sweep".into(),
        ));
    }
    let methods = compare.map(|c| parse_methods(&c)).transpose()?;
    let lambdas = sweep.map(|s| parse_list("--sweep", &s)).transpose()?;
    let display = options::load_path(&display_path, "display")?;
    let camera = options::load_path(&background_path, "background")?;
    let inputs = Inputs {
        display,
        camera,
        params,
        engine,
        json,
        figure,
        app_images,
        ppd,
    };
    match (lambdas, methods) {
        (Some(l), _) => run_sweep(&inputs, &l),
        (None, Some(m)) => run_compare(&inputs, &m),
        (None, None) => run_single(&inputs, enhanced.as_deref()),
    }
}

fn enhanced_image(
    inputs: &Inputs,
    path: Option<&str>,
    params: &Params,
) -> Result<RgbaImage, CliError> {
    let Some(path) = path else {
        return backend_choice::run(
            inputs.engine,
            &inputs.display,
            &inputs.camera,
            params,
            inputs.ppd,
        )
        .map_err(CliError::Failure);
    };
    let img = options::load_path(path, "enhanced")?;
    let (d, e) = (&inputs.display, &img);
    if (d.width, d.height) != (e.width, e.height) {
        return Err(CliError::Failure(format!(
            "the enhanced image is {}x{} but the display image is {}x{}; they must match",
            e.width, e.height, d.width, d.height
        )));
    }
    Ok(img)
}

/// The paper's metric and the perceived contrast, over the same prepared background.
struct Measured {
    metrics: Metrics,
    perception: PerceptionReport,
}

impl Measured {
    /// Both as one JSON object (the metric's keys, then the perceived contrast's).
    fn json(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(&self.metrics).expect("metrics serialise");
        let p = serde_json::to_value(&self.perception).expect("the report serialises");
        if let (Some(v), serde_json::Value::Object(p)) = (v.as_object_mut(), p) {
            v.extend(p);
        }
        v
    }
}

fn measure(inputs: &Inputs, enhanced: &RgbaImage, params: &Params) -> Measured {
    let d = &inputs.display;
    let bg = background_preparation::prepare(&inputs.camera, d.width, d.height, params);
    let frequencies = offline_frequencies(params, d.width, inputs.camera.width, inputs.ppd);
    Measured {
        metrics: eval::metrics(d, enhanced, &bg),
        perception: eval::perception_report(d, enhanced, &bg, params, frequencies),
    }
}

fn run_single(inputs: &Inputs, path: Option<&str>) -> Result<(), CliError> {
    let enhanced = enhanced_image(inputs, path, &inputs.params)?;
    let m = measure(inputs, &enhanced, &inputs.params);
    if inputs.json {
        super::error::print(&format!(
            "{}\n",
            serde_json::to_string_pretty(&m.json()).expect("metrics serialise")
        ));
    } else {
        super::error::print(
            &(metrics_text(&m.metrics) + &perception_text(&m.perception, &inputs.params)),
        );
    }
    if let Some(fig) = &inputs.figure {
        let img = if inputs.app_images {
            eval::figure_with_app_images(&inputs.display, &enhanced, &inputs.camera, &inputs.params)
        } else {
            eval::figure(&inputs.display, &enhanced, &inputs.camera, &inputs.params)
        };
        options::save_image(&img, fig)?;
    }
    Ok(())
}

fn metrics_text(m: &Metrics) -> String {
    let mut out = format!(
        "enhanced pixels: {} of {} foreground pixels ({:.2}%)\n",
        m.enhanced_pixels, m.foreground_pixels, m.enhanced_percent
    );
    out += &format!(
        "{:<22} {:>8} {:>8} {:>8}\n",
        "Delta E*ab", "min", "mean", "max"
    );
    for (name, s) in [
        ("output vs display", m.delta_e_out_display),
        ("background vs display", m.delta_e_bg_display),
        ("background vs output", m.delta_e_bg_out),
    ] {
        out += &format!("{name:<22} {:>8.3} {:>8.3} {:>8.3}\n", s.min, s.mean, s.max);
    }
    out
}

/// The perceived contrast in three lines (`enhance` prints them too).
pub(super) fn perception_text(p: &PerceptionReport, params: &Params) -> String {
    let s = &params.perceptual;
    let cpd: Vec<String> = p.frequency_cpd.iter().map(|f| format!("{f:.2}")).collect();
    let mut out = format!(
        "perceived contrast c' (display {} cd/m², world {} cd/m², frequency {}: {} cpd): \
         {:.4} -> {:.4} (x{:.3})\n",
        s.display_peak_nits,
        s.world_nits,
        p.frequency,
        cpd.join(", "),
        p.perceived_contrast_before,
        p.perceived_contrast_after,
        p.perceived_contrast_gain
    );
    out += &format!(
        "target c' {}: left alone {:.2}%, brought to target {:.2}%, out of reach {:.2}%\n",
        p.target_contrast,
        100.0 * p.left_alone_fraction,
        100.0 * p.brought_to_target_fraction,
        100.0 * p.out_of_reach_fraction
    );
    out += &format!(
        "world behind the content: {:.1} cd/m² at the eye\n",
        p.mean_world_luminance
    );
    out
}

fn run_sweep(inputs: &Inputs, lambdas: &[f32]) -> Result<(), CliError> {
    let mut rows = Vec::new();
    let mut figure_rows = Vec::new();
    for &lambda_e in lambdas {
        let params = Params {
            lambda_e,
            ..inputs.params.clone()
        };
        params.validate().map_err(CliError::Failure)?;
        let enhanced = enhanced_image(inputs, None, &params)?;
        rows.push((lambda_e, measure(inputs, &enhanced, &params)));
        if inputs.figure.is_some() {
            let title = format!("λE = {lambda_e}   METHOD {}", params.method.name());
            let d = &inputs.display;
            figure_rows.push(eval::figure_row(
                d,
                &enhanced,
                &inputs.camera,
                &params,
                Some(&title),
            ));
        }
    }
    super::error::print(&if inputs.json {
        sweep_json(&rows)
    } else {
        sweep_table(&rows)
    });
    if let Some(fig) = &inputs.figure {
        options::save_image(&eval::stack_rows(&figure_rows), fig)?;
    }
    Ok(())
}

/// `--compare`'s list: method names, at least one.
fn parse_methods(text: &str) -> Result<Vec<Method>, CliError> {
    text.split(',')
        .map(|name| {
            Method::parse(name.trim()).ok_or_else(|| {
                CliError::Usage(format!(
                    "--compare: '{}' is not a method ({})",
                    name.trim(),
                    contrastxr::algorithm::method::METHOD_DOC
                ))
            })
        })
        .collect()
}

/// Each method on the same inputs: a row each (text or JSON), and the figure's rows.
fn run_compare(inputs: &Inputs, methods: &[Method]) -> Result<(), CliError> {
    let mut rows = Vec::new();
    let mut figure_rows = Vec::new();
    for &method in methods {
        let params = Params {
            method,
            ..inputs.params.clone()
        };
        let enhanced = enhanced_image(inputs, None, &params)?;
        let m = measure(inputs, &enhanced, &params);
        if inputs.figure.is_some() {
            let d = &inputs.display;
            let bg = background_preparation::prepare(&inputs.camera, d.width, d.height, &params);
            let frequencies =
                offline_frequencies(&params, d.width, inputs.camera.width, inputs.ppd);
            let p = &m.perception;
            let title = format!(
                "METHOD {}   PERCEIVED CONTRAST X{:.3}   AT TARGET {:.1}%   MEAN DE {:.2}",
                method.name(),
                p.perceived_contrast_gain,
                100.0 * (p.left_alone_fraction + p.brought_to_target_fraction),
                m.metrics.delta_e_out_display.mean
            );
            let model = perception_model(&params, frequencies);
            figure_rows.push(class_row(
                (d, &enhanced, &inputs.camera),
                &bg,
                &params,
                &model,
                &title,
            ));
        }
        rows.push((method, m));
    }
    super::error::print(&if inputs.json {
        let values: Vec<serde_json::Value> = rows
            .iter()
            .map(|(method, m)| {
                let mut v = m.json();
                v["method"] = serde_json::json!(method.name());
                v
            })
            .collect();
        format!(
            "{}\n",
            serde_json::to_string_pretty(&values).expect("rows serialise")
        )
    } else {
        compare_table(&rows)
    });
    if let Some(fig) = &inputs.figure {
        options::save_image(&eval::stack_rows(&figure_rows), fig)?;
    }
    Ok(())
}

fn compare_table(rows: &[(Method, Measured)]) -> String {
    let mut out = format!(
        "{:>12} {:>9} {:>9} {:>8} {:>11} {:>12} {:>13} {:>13}\n",
        "method",
        "c' before",
        "c' after",
        "c' gain",
        "at target",
        "out of reach",
        "mean dE(out,D)",
        "max dE(out,D)"
    );
    for (method, m) in rows {
        let (p, s) = (&m.perception, &m.metrics.delta_e_out_display);
        out += &format!(
            "{:>12} {:>9.4} {:>9.4} {:>8.3} {:>10.1}% {:>11.1}% {:>14.3} {:>13.3}\n",
            method.name(),
            p.perceived_contrast_before,
            p.perceived_contrast_after,
            p.perceived_contrast_gain,
            100.0 * (p.left_alone_fraction + p.brought_to_target_fraction),
            100.0 * p.out_of_reach_fraction,
            s.mean,
            s.max
        );
    }
    out
}

fn sweep_json(rows: &[(f32, Measured)]) -> String {
    let values: Vec<serde_json::Value> = rows
        .iter()
        .map(|(l, m)| {
            let mut v = m.json();
            v["lambda_e"] = serde_json::json!(l);
            v
        })
        .collect();
    format!(
        "{}\n",
        serde_json::to_string_pretty(&values).expect("rows serialise")
    )
}

fn sweep_table(rows: &[(f32, Measured)]) -> String {
    let mut out = format!(
        "{:>8} {:>10} {:>10} {:>9} {:>14} {:>14} {:>9}\n",
        "lambda_e",
        "foreground",
        "enhanced",
        "percent",
        "mean dE(out,D)",
        "mean dE(B,out)",
        "c' gain"
    );
    for (l, m) in rows {
        let (p, m) = (&m.perception, &m.metrics);
        out += &format!(
            "{l:>8} {:>10} {:>10} {:>8.2}% {:>14.3} {:>14.3} {:>9.3}\n",
            m.foreground_pixels,
            m.enhanced_pixels,
            m.enhanced_percent,
            m.delta_e_out_display.mean,
            m.delta_e_bg_out.mean,
            p.perceived_contrast_gain
        );
    }
    out
}
