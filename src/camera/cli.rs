//! `contrastxr camera list` and `contrastxr camera test`, as library functions the binary calls.

use crate::camera::v4l2::{self, device_dir, device_nodes, probe, Mode};
use crate::camera::{parse_source, Background, CaptureConfig, Frame, SourceSpec};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Lists V4L2 devices with their formats, sizes and rates.
pub fn list(out: &mut dyn Write) -> Result<(), String> {
    list_in(&device_dir(), out)
}

/// [`list`] for the `video*` nodes of `dir`.
pub fn list_in(dir: &Path, out: &mut dyn Write) -> Result<(), String> {
    let w = |e: std::io::Error| format!("cannot write the list: {e}");
    let nodes = device_nodes(dir);
    let mut captures = 0;
    for path in &nodes {
        match probe(path) {
            Err(e) => writeln!(out, "{}: cannot open: {e}", path.display()).map_err(w)?,
            Ok((_, info)) if !info.capture => writeln!(
                out,
                "{}: {} ({}), not a video capture node",
                path.display(),
                info.card,
                info.driver
            )
            .map_err(w)?,
            Ok((device, info)) => {
                captures += 1;
                writeln!(
                    out,
                    "{}: {} ({}, {})",
                    path.display(),
                    info.card,
                    info.driver,
                    info.bus
                )
                .map_err(w)?;
                for stable in v4l2::stable_paths(dir, path) {
                    writeln!(out, "  also {}", stable.display()).map_err(w)?;
                }
                for control in v4l2::controls::describe(&device) {
                    writeln!(out, "  control {control}").map_err(w)?;
                }
                match v4l2::modes(&device) {
                    Ok(modes) => write_modes(&modes, out).map_err(w)?,
                    Err(e) => writeln!(out, "  cannot list formats: {e}").map_err(w)?,
                }
            }
        }
    }
    if captures == 0 {
        let why = if nodes.is_empty() {
            "absent"
        } else {
            "not capture devices"
        };
        writeln!(
            out,
            "no V4L2 capture device found ({}/video* {why})",
            dir.display()
        )
        .map_err(w)?;
    }
    Ok(())
}

/// Frame rates offered at each (width, height).
type RatesBySize = BTreeMap<(u32, u32), Vec<f64>>;

fn write_modes(modes: &[Mode], out: &mut dyn Write) -> std::io::Result<()> {
    let mut by_format: BTreeMap<[u8; 4], RatesBySize> = BTreeMap::new();
    for m in modes {
        by_format
            .entry(m.fourcc)
            .or_default()
            .entry((m.width, m.height))
            .or_default()
            .push(m.fps());
    }
    for (fourcc, sizes) in by_format {
        let usable = if crate::camera::convert::PixelFormat::from_fourcc(fourcc).is_some() {
            ""
        } else {
            " (not usable as a background)"
        };
        writeln!(out, "  {}{usable}", String::from_utf8_lossy(&fourcc))?;
        for ((width, height), rates) in sizes {
            let rates: Vec<String> = rates
                .iter()
                .map(|r| {
                    if *r > 0.0 {
                        format!("{r:.4}")
                            .trim_end_matches('0')
                            .trim_end_matches('.')
                            .to_string()
                    } else {
                        "?".into()
                    }
                })
                .collect();
            writeln!(out, "    {width}x{height} at {} fps", rates.join(", "))?;
        }
    }
    Ok(())
}

/// Opens `device` (`/dev/videoN`, `auto` or a `v4l2:` spec) as the layer would, takes `frames`
/// new frames, reports the achieved rate and latency, and saves them as PNG into `out_dir`.
pub fn test(
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
    let span = last
        .captured_at
        .saturating_duration_since(first.captured_at)
        .as_secs_f64();
    let rate = if span > 0.0 {
        (got.len() - 1) as f64 / span
    } else {
        0.0
    };
    let latencies: Vec<f64> = got
        .iter()
        .map(|(f, seen)| seen.saturating_duration_since(f.captured_at).as_secs_f64() * 1000.0)
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
