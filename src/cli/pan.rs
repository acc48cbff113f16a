//! `contrastxr pan`: a moving background for `video:` without a camera: numbered PNG frames of
//! a window sliding across images put side by side, and back, so that the video loops smoothly.

use contrastxr::image::RgbaImage;
use std::path::Path;

use super::args::Args;
use super::args::Opt;
use super::error::CliError;
use super::options;

pub const OPTIONS: &[Opt] = &[
    Opt::value("--output", "DIR").short('o'),
    Opt::value("--frames", "N"),
];

const USAGE: &str = "\
usage: contrastxr pan IMAGE... -o DIR [--frames N]

Puts the images (all of one height) side by side and writes N frames (DIR/frame-0000.png, ...)
of a window the first image's size that slides, eased, from the left end to the right end and
back: a looping video for CONTRASTXR_BACKGROUND=video:DIR, which the layer plays at 30 frames
per second.
  --frames N    how many frames (90: three seconds at 30 frames per second)
  -o DIR        the folder to write (created; it must hold no PNG files yet)
";

pub fn usage() -> String {
    USAGE.to_string()
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let out = args.required(&["-o", "--output"])?;
    let frames = match args.value(&["--frames"])? {
        None => 90,
        Some(v) => v
            .trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n >= 2)
            .ok_or_else(|| {
                CliError::Failure(format!(
                    "--frames must be a whole number of 2 or more, got '{v}'"
                ))
            })?,
    };
    let paths = args.positional();
    args.finish()?;
    if paths.is_empty() {
        return Err(CliError::Usage("pan needs at least one IMAGE".into()));
    }
    let images = paths
        .iter()
        .map(|p| options::load_path(p, "pan"))
        .collect::<Result<Vec<_>, _>>()?;
    let strip = side_by_side(&images)?;
    let window = images[0].width;
    if strip.width <= window {
        return Err(CliError::Failure(
            "nothing to pan across: give two or more images".into(),
        ));
    }
    let dir = Path::new(&out);
    prepare_dir(dir)?;
    for i in 0..frames {
        let x = window_x(i, frames, strip.width - window);
        let frame = crop(&strip, x, window);
        options::save_image(
            &frame,
            &dir.join(format!("frame-{i:04}.png")).to_string_lossy(),
        )?;
    }
    super::error::print(&format!(
        "pan: {frames} frames of {window}x{} in {out} (video:{out})\n",
        strip.height
    ));
    Ok(())
}

/// The left edge of frame `i` of `n`: eased from 0 to `span` and back, so frame n would be
/// frame 0 again.
fn window_x(i: u32, n: u32, span: u32) -> u32 {
    let phase = f64::from(i) / f64::from(n);
    let eased = (1.0 - (std::f64::consts::TAU * phase).cos()) / 2.0;
    (eased * f64::from(span)).round() as u32
}

fn side_by_side(images: &[RgbaImage]) -> Result<RgbaImage, CliError> {
    let height = images[0].height;
    if images.iter().any(|i| i.height != height) {
        return Err(CliError::Failure(
            "the images to pan across must have the same height".into(),
        ));
    }
    let width = images.iter().map(|i| i.width).sum();
    let mut strip = RgbaImage::new(width, height, [0, 0, 0, 255]);
    strip.has_alpha = false;
    let mut x0 = 0;
    for img in images {
        for y in 0..height {
            for x in 0..img.width {
                let [r, g, b, _] = img.get(x, y);
                strip.set(x0 + x, y, [r, g, b, 255]);
            }
        }
        x0 += img.width;
    }
    Ok(strip)
}

fn crop(strip: &RgbaImage, x0: u32, width: u32) -> RgbaImage {
    let mut out = RgbaImage::new(width, strip.height, [0, 0, 0, 255]);
    out.has_alpha = false;
    for y in 0..strip.height {
        for x in 0..width {
            out.set(x, y, strip.get(x0 + x, y));
        }
    }
    out
}

fn prepare_dir(dir: &Path) -> Result<(), CliError> {
    let fail =
        |e: std::io::Error| CliError::Failure(format!("cannot write {}: {e}", dir.display()));
    std::fs::create_dir_all(dir).map_err(fail)?;
    let has_png = std::fs::read_dir(dir).map_err(fail)?.any(|e| {
        e.is_ok_and(|e| {
            e.path()
                .extension()
                .is_some_and(|x| x.eq_ignore_ascii_case("png"))
        })
    });
    if has_png {
        return Err(CliError::Failure(format!(
            "{} already holds PNG files: a video folder is all its PNG files; use an empty folder",
            dir.display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_goes_to_the_end_and_back() {
        assert_eq!(window_x(0, 90, 960), 0);
        assert_eq!(window_x(45, 90, 960), 960);
        assert!(window_x(20, 90, 960) > window_x(10, 90, 960));
        assert_eq!(window_x(30, 90, 960), window_x(60, 90, 960));
    }
}
