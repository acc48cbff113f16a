//! `contrastxr camera list` and `contrastxr camera test DEVICE [--frames N] [-o DIR]`: how a
//! user checks their camera before putting on the headset.

use super::args::{Args, Opt};
use super::error::CliError;
use contrastxr::camera::v4l2::{self, device_dir};
use contrastxr::camera::{parse_source, Background, CaptureConfig, Frame, SourceSpec};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub const OPTIONS: &[Opt] = &[
    Opt::value("--frames", "N"),
    Opt::value("--output", "DIR").short('o'),
];

pub fn usage() -> String {
    "usage: contrastxr camera list\n\
     \x20      contrastxr camera test DEVICE [--frames N] [-o DIR]\n\n\
     list: V4L2 capture devices with their formats, sizes and frame rates.\n\
     test: opens DEVICE (/dev/videoN or auto) as the layer would, reports the achieved rate\n\
     and latency, and with -o saves the frames as PNG into DIR.\n"
        .to_string()
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let frames = args.value(&["--frames"])?;
    let out_dir = args.value(&["-o", "--output"])?.map(PathBuf::from);
    let rest = args.positional();
    args.finish()?;
    let mut out = std::io::stdout().lock();
    match rest.as_slice() {
        [cmd] if cmd == "list" => list(&mut out).map_err(CliError::Failure),
        [cmd, device] if cmd == "test" => {
            let frames = match frames {
                Some(f) => f
                    .parse()
                    .map_err(|_| CliError::Usage(format!("--frames {f:?} is not a count")))?,
                None => 30,
            };
            test(device, frames, out_dir.as_deref(), &mut out).map_err(CliError::Failure)
        }
        _ => Err(CliError::Usage(
            "expected `camera list` or `camera test DEVICE`".into(),
        )),
    }
}

/// Lists the V4L2 devices (the `video*` nodes of [`device_dir`]) with their formats, sizes
/// and rates.
fn list(out: &mut dyn Write) -> Result<(), String> {
    out.write_all(v4l2::listing(&device_dir()).as_bytes())
        .map_err(|e| format!("cannot write the list: {e}"))
}

/// Opens `device` (`/dev/videoN`, `auto` or a `v4l2:` spec) as the layer would, takes `frames`
/// new frames, reports the achieved rate and latency, and saves them as PNG into `out_dir`.
fn test(
    device: &str,
    frames: u32,
    out_dir: Option<&Path>,
    out: &mut dyn Write,
) -> Result<(), String> {
    let w = |e: std::io::Error| format!("cannot write the report: {e}");
    let spec = match device {
        "auto" => SourceSpec::V4l2Auto,
        d if d.starts_with("v4l2:") => parse_source(d)?,
        d => SourceSpec::V4l2Device(PathBuf::from(d)),
    };
    let background =
        Background::open(&spec, &CaptureConfig::default()).map_err(|e| e.to_string())?;
    writeln!(out, "opened {}", background.description()).map_err(w)?;
    let wanted = frames.max(1) as usize;
    // Generous: a camera that cannot manage 5 fps plus a few seconds to start is not usable.
    let deadline =
        Instant::now() + Duration::from_secs(5) + Duration::from_millis(200) * wanted as u32;
    let got = collect(&background, wanted, deadline);
    drop(background); // the camera is closed before anything is written
    report(&got, out).map_err(w)?;
    if let Some(dir) = out_dir {
        save(&got, dir, out)?;
    }
    if got.len() < wanted {
        return Err(format!(
            "only {} of {wanted} frames arrived in time",
            got.len()
        ));
    }
    Ok(())
}

/// New frames with the moment each became visible to a reader.
fn collect(background: &Background, wanted: usize, deadline: Instant) -> Vec<(Frame, Instant)> {
    let mut got: Vec<(Frame, Instant)> = Vec::new();
    while got.len() < wanted && Instant::now() < deadline {
        match background.latest() {
            Some(f)
                if got
                    .last()
                    .is_none_or(|(last, _)| f.sequence > last.sequence) =>
            {
                got.push((f, Instant::now()))
            }
            _ => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    got
}

fn report(got: &[(Frame, Instant)], out: &mut dyn Write) -> std::io::Result<()> {
    let (Some((first, _)), Some((last, _))) = (got.first(), got.last()) else {
        return writeln!(out, "no frame arrived");
    };
    // A still image was captured at no moment: it counts as captured when seen.
    let captured = |(f, seen): &(Frame, Instant)| f.captured_at.unwrap_or(*seen);
    let span = captured(&got[got.len() - 1])
        .saturating_duration_since(captured(&got[0]))
        .as_secs_f64();
    let rate = if span > 0.0 {
        (got.len() - 1) as f64 / span
    } else {
        0.0
    };
    let latencies: Vec<f64> = got
        .iter()
        .map(|g| g.1.saturating_duration_since(captured(g)).as_secs_f64() * 1000.0)
        .collect();
    let mean = latencies.iter().sum::<f64>() / latencies.len() as f64;
    let max = latencies.iter().copied().fold(0.0, f64::max);
    let skipped = last.sequence - first.sequence + 1 - got.len() as u64;
    let (w, h) = (first.image.width, first.image.height);
    writeln!(
        out,
        "{} frames of {w}x{h} at {rate:.1} fps ({skipped} skipped)",
        got.len()
    )?;
    writeln!(
        out,
        "latency from capture to the reader: mean {mean:.1} ms, max {max:.1} ms"
    )
}

fn save(got: &[(Frame, Instant)], dir: &Path, out: &mut dyn Write) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    for (i, (frame, _)) in got.iter().enumerate() {
        frame
            .image
            .save_png(&dir.join(format!("frame-{i:04}.png")))?;
    }
    writeln!(out, "saved {} frames to {}", got.len(), dir.display())
        .map_err(|e| format!("cannot write the report: {e}"))
}
