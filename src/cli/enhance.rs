//! `contrastxr enhance`: one display image against one background image, to a PNG, and the
//! perceived contrast of the content before and after (docs/algorithm.md, *What it reports*).

use std::time::Instant;

use contrastxr::background_preparation;
use contrastxr::evaluate::perception_report::{offline_frequencies, perception_report};

use super::args::{Args, Opt};
use super::backend_choice;
use super::error::CliError;
use super::evaluate::perception_text;
use super::options::{self, method_usage, ppd_usage, ENGINE_USAGE};

pub const OPTIONS: &[Opt] = &[
    Opt::value("--display", "D.png"),
    Opt::value("--background", "B.png"),
    Opt::value("--output", "OUT.png").short('o'),
];

const USAGE: &str =
    "usage: contrastxr enhance --display D.png --background B.png -o OUT.png [options]\n\n\
     Enhances the colour contrast of the display image (virtual content; black is transparent)\n\
     against the background image (a camera frame of any size). PNG or JPEG in, PNG out,\n\
     RGB or RGBA; alpha passes through and the output has the display's layout. Then prints the\n\
     perceived contrast c' of the content before and after, as `evaluate` does.\n\n";

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let display_path = args.required(&["--display"])?;
    let background_path = args.required(&["--background"])?;
    let out_path = args.required(&["-o", "--output"])?;
    let ppd = options::pixels_per_degree(args)?;
    let params = options::params(args)?;
    let engine = options::engine(args)?;
    args.finish()?;
    let display = options::load_path(&display_path, "display")?;
    let camera = options::load_path(&background_path, "background")?;
    let start = Instant::now();
    let out =
        backend_choice::run(engine, &display, &camera, &params, ppd).map_err(CliError::Failure)?;
    let seconds = start.elapsed().as_secs_f64();
    options::save_image(&out, &out_path)?;
    super::error::print(&format!(
        "wrote {out_path} ({}x{}, method {}, lambda_e {}, {} engine, {seconds:.3} s)\n",
        out.width,
        out.height,
        params.method.name(),
        params.lambda_e,
        engine.name()
    ));
    let background = background_preparation::prepare(&camera, out.width, out.height, &params);
    let frequencies = offline_frequencies(&params, out.width, camera.width, ppd);
    let report = perception_report(&display, &out, &background, &params, frequencies);
    super::error::print(&perception_text(&report, &params));
    Ok(())
}

/// Full help text (the options block is shared with `evaluate`).
pub fn usage() -> String {
    format!("{USAGE}{}\n{}{ENGINE_USAGE}", ppd_usage(), method_usage())
}
