//! The V4L2 devices as text, one block per node: its card, driver and bus, its stable paths,
//! its controls, and its formats with their sizes and frame rates. What `contrastxr camera
//! list` prints; built here, beside what it describes, so that it reads the devices exactly as
//! the capture thread opens them.

use super::choose::Mode;
use super::controls;
use super::devices::{device_nodes, modes, probe, stable_paths};
use crate::camera::convert::PixelFormat;
use std::collections::BTreeMap;
use std::path::Path;

/// The `video*` nodes of `dir` (see [`super::device_dir`]), each line ending in a newline;
/// a line saying so when none of them is a capture device.
pub fn listing(dir: &Path) -> String {
    let mut lines = Vec::new();
    let nodes = device_nodes(dir);
    let mut captures = 0;
    for path in &nodes {
        match probe(path) {
            Err(e) => lines.push(format!("{}: cannot open: {e}", path.display())),
            Ok((_, info)) if !info.capture => lines.push(format!(
                "{}: {} ({}), not a video capture node",
                path.display(),
                info.card,
                info.driver
            )),
            Ok((device, info)) => {
                captures += 1;
                lines.push(format!(
                    "{}: {} ({}, {})",
                    path.display(),
                    info.card,
                    info.driver,
                    info.bus
                ));
                for stable in stable_paths(dir, path) {
                    lines.push(format!("  also {}", stable.display()));
                }
                for control in controls::describe(&device) {
                    lines.push(format!("  control {control}"));
                }
                match modes(&device) {
                    Ok(modes) => mode_lines(&modes, &mut lines),
                    Err(e) => lines.push(format!("  cannot list formats: {e}")),
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
        lines.push(format!(
            "no V4L2 capture device found ({}/video* {why})",
            dir.display()
        ));
    }
    lines.iter().map(|l| format!("{l}\n")).collect()
}

/// Frame rates offered at each (width, height).
type RatesBySize = BTreeMap<(u32, u32), Vec<f64>>;

fn mode_lines(modes: &[Mode], lines: &mut Vec<String>) {
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
        let usable = if PixelFormat::from_fourcc(fourcc).is_some() {
            ""
        } else {
            " (not usable as a background)"
        };
        lines.push(format!("  {}{usable}", String::from_utf8_lossy(&fourcc)));
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
            lines.push(format!("    {width}x{height} at {} fps", rates.join(", ")));
        }
    }
}
