//! `contrastxr animate`: an animated figure (APNG) from the layer's captures of consecutive
//! frames (`CONTRASTXR_CAPTURE_DIR` with `capture_frames` above 1), each frame the panels of
//! `evaluate --figure --app-images`, shown for as long as the app's frames were apart.

use contrastxr::evaluate::{self as eval, AnimationFrame};
use std::path::{Path, PathBuf};

use super::args::Args;
use super::args::Opt;
use super::error::CliError;
use super::options::{self, method_usage};

pub const OPTIONS: &[Opt] = &[
    Opt::value("--captures", "DIR"),
    Opt::value("--output", "ANIM.png").short('o'),
    Opt::value("--view", "N"),
    Opt::value("--frames", "N"),
    Opt::value("--panel-width", "W"),
];

const USAGE: &str = "\
usage: contrastxr animate --captures DIR -o ANIM.png [--view N] [--frames N] [--panel-width W]

Writes an animated PNG (APNG, looping) from the layer's captures in DIR (the files
frame-F-view-V-{display,output,background}.png and .json that CONTRASTXR_CAPTURE_DIR with
CONTRASTXR_CAPTURE_FRAMES above 1 writes): each frame shows the app's image, the enhanced image,
the simulated perceived views before and after, and the enhanced pixels, and stays as long as
the app's frames were apart (their display times).
  --view N             which view (eye) to show (0)
  --frames N           at most this many frames, evenly spread over the captures (30)
  --panel-width W      panels are shrunk by an integer factor to at most W pixels wide (320)

";

const DEFAULT_DELAY_MS: u16 = 100;

pub fn usage() -> String {
    format!("{USAGE}{}", method_usage())
}

/// One captured frame of the chosen view: its file stem and display time.
struct Capture {
    stem: PathBuf,
    display_time_ns: Option<i64>,
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let dir = args.required(&["--captures"])?;
    let out = args.required(&["-o", "--output"])?;
    let view = count(args, "--view", 0)?;
    let max_frames = count(args, "--frames", 30)?.max(1);
    let panel_width = count(args, "--panel-width", 320)?.max(16) as u32;
    let params = options::params(args)?;
    args.finish()?;
    let captures = pick(&captures(Path::new(&dir), view)?, max_frames);
    let delays = delays_ms(&captures);
    let mut frames = Vec::new();
    for (c, delay_ms) in captures.iter().zip(delays) {
        let load = |suffix: &str| {
            let path = format!("{}-{suffix}.png", c.stem.display());
            options::load_path(&path, suffix)
        };
        let (display, output, background) =
            (load("display")?, load("output")?, load("background")?);
        let image =
            eval::figure_with_app_images_at(&display, &output, &background, &params, panel_width);
        frames.push(AnimationFrame { image, delay_ms });
    }
    let bytes = eval::encode_apng(&frames).map_err(CliError::Failure)?;
    std::fs::write(&out, bytes)
        .map_err(|e| CliError::Failure(format!("cannot write {out}: {e}")))?;
    let total: u32 = frames.iter().map(|f| u32::from(f.delay_ms)).sum();
    super::error::print(&format!(
        "animation: {} frames, {:.1} s, {}x{}: {out}\n",
        frames.len(),
        f64::from(total) / 1e3,
        frames[0].image.width,
        frames[0].image.height
    ));
    Ok(())
}

fn count(args: &mut Args, name: &str, default: usize) -> Result<usize, CliError> {
    match args.value(&[name])? {
        None => Ok(default),
        Some(v) => v
            .trim()
            .parse()
            .map_err(|_| CliError::Failure(format!("{name} must be a whole number, got '{v}'"))),
    }
}

/// The captures of `view` in `dir`, in frame order.
fn captures(dir: &Path, view: usize) -> Result<Vec<Capture>, CliError> {
    contrastxr::user_file::folder(dir)
        .map_err(|why| CliError::Failure(format!("capture folder {} {why}", dir.display())))?;
    let entries = std::fs::read_dir(dir)
        .map_err(|e| CliError::Failure(format!("cannot read {}: {e}", dir.display())))?;
    let suffix = format!("-view-{view}.json");
    let mut found: Vec<(u64, Capture)> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let frame = name.strip_prefix("frame-")?.strip_suffix(&suffix)?;
            let frame: u64 = frame.parse().ok()?;
            let stem = dir.join(format!("frame-{frame}-view-{view}"));
            Some((frame, capture(stem, &e.path())))
        })
        .collect();
    if found.is_empty() {
        return Err(CliError::Failure(format!(
            "{} holds no captures of view {view} (frame-N-view-{view}.json)",
            dir.display()
        )));
    }
    found.sort_by_key(|(frame, _)| *frame);
    Ok(found.into_iter().map(|(_, c)| c).collect())
}

fn capture(stem: PathBuf, json: &Path) -> Capture {
    let display_time_ns = contrastxr::user_file::read(json, contrastxr::user_file::TEXT_BYTES)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| v["display_time"].as_i64());
    Capture {
        stem,
        display_time_ns,
    }
}

/// At most `n` captures, evenly spread from the first to the last.
fn pick(all: &[Capture], n: usize) -> Vec<Capture> {
    let k = n.min(all.len());
    (0..k)
        .map(|i| {
            if k == 1 {
                0
            } else {
                i * (all.len() - 1) / (k - 1)
            }
        })
        .map(|i| Capture {
            stem: all[i].stem.clone(),
            display_time_ns: all[i].display_time_ns,
        })
        .collect()
}

/// Each frame stays until the next one's display time; the last as long as the average.
fn delays_ms(captures: &[Capture]) -> Vec<u16> {
    let mut delays: Vec<u16> = captures
        .windows(2)
        .map(|w| match (w[0].display_time_ns, w[1].display_time_ns) {
            (Some(a), Some(b)) if b > a => ((b - a) / 1_000_000).clamp(10, 5000) as u16,
            _ => DEFAULT_DELAY_MS,
        })
        .collect();
    let average = match delays.len() {
        0 => DEFAULT_DELAY_MS,
        n => (delays.iter().map(|&d| u32::from(d)).sum::<u32>() / n as u32) as u16,
    };
    delays.push(average);
    delays
}
