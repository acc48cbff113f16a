//! Finding V4L2 capture devices: their nodes, their stable paths, what they are and the modes
//! they offer. Device nodes are looked up in `/dev`, or in the folder named by
//! `CONTRASTXR_V4L2_DIR`.

use super::choose::Mode;
use crate::camera::convert::PixelFormat;
use std::io;
use std::path::{Path, PathBuf};
use v4l::capability::Flags;
use v4l::frameinterval::FrameIntervalEnum;
use v4l::framesize::FrameSizeEnum;
use v4l::video::Capture;
use v4l::{Device, FourCC};

/// Where device nodes live: `$CONTRASTXR_V4L2_DIR` or `/dev`.
pub fn device_dir() -> PathBuf {
    std::env::var_os("CONTRASTXR_V4L2_DIR").map_or_else(|| PathBuf::from("/dev"), PathBuf::from)
}

/// The `video*` nodes of `dir`, in numeric order (video2 before video10).
pub fn device_nodes(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut nodes: Vec<(u64, PathBuf)> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let number = name.strip_prefix("video")?.parse().ok()?;
            Some((number, e.path()))
        })
        .collect();
    nodes.sort();
    nodes.into_iter().map(|(_, p)| p).collect()
}

/// What a device node says about itself.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub path: PathBuf,
    pub card: String,
    pub driver: String,
    pub bus: String,
    /// Whether it is a video capture node (UVC cameras also expose metadata nodes).
    pub capture: bool,
}

pub fn probe(path: &Path) -> io::Result<(Device, DeviceInfo)> {
    let device = Device::with_path(path)?;
    let caps = device.query_caps()?;
    let info = DeviceInfo {
        path: path.to_path_buf(),
        card: caps.card,
        driver: caps.driver,
        bus: caps.bus,
        capture: caps.capabilities.contains(Flags::VIDEO_CAPTURE)
            && caps.capabilities.contains(Flags::STREAMING),
    };
    Ok((device, info))
}

/// The stable names of a device node: links to it in `dir`/v4l/by-id and by-path (udev's),
/// which keep naming the same camera when /dev/videoN numbers change across reboots.
pub fn stable_paths(dir: &Path, node: &Path) -> Vec<PathBuf> {
    let Ok(target) = std::fs::canonicalize(node) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for kind in ["by-id", "by-path"] {
        let Ok(entries) = std::fs::read_dir(dir.join("v4l").join(kind)) else {
            continue;
        };
        let mut links: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| std::fs::canonicalize(p).is_ok_and(|t| t == target))
            .collect();
        links.sort();
        out.extend(links);
    }
    out
}

/// Every (format, size, frame interval) the device offers, including formats this module
/// cannot convert (`format` is then `None`, so `camera list` can still show them).
pub fn modes(device: &Device) -> io::Result<Vec<Mode>> {
    let mut modes = Vec::new();
    for desc in device.enum_formats()? {
        for (width, height) in sizes(device, desc.fourcc)? {
            for interval in intervals(device, desc.fourcc, width, height)? {
                modes.push(Mode {
                    fourcc: desc.fourcc.repr,
                    format: PixelFormat::from_fourcc(desc.fourcc.repr),
                    width,
                    height,
                    interval,
                });
            }
        }
    }
    Ok(modes)
}

/// Discrete sizes as listed; a stepwise range contributes its smallest, its largest and
/// 640x480 when that lies on its grid (enough to choose from without listing thousands).
fn sizes(device: &Device, fourcc: FourCC) -> io::Result<Vec<(u32, u32)>> {
    let mut out = Vec::new();
    for size in device.enum_framesizes(fourcc)? {
        match size.size {
            FrameSizeEnum::Discrete(d) => out.push((d.width, d.height)),
            FrameSizeEnum::Stepwise(s) => {
                out.push((s.min_width, s.min_height));
                let on_grid = |v: u32, min: u32, max: u32, step: u32| {
                    v >= min && v <= max && (v - min).is_multiple_of(step.max(1))
                };
                if on_grid(640, s.min_width, s.max_width, s.step_width)
                    && on_grid(480, s.min_height, s.max_height, s.step_height)
                {
                    out.push((640, 480));
                }
                out.push((s.max_width, s.max_height));
            }
        }
    }
    out.dedup();
    Ok(out)
}

/// Frame intervals as (numerator, denominator) seconds; a stepwise range gives its ends.
fn intervals(device: &Device, fourcc: FourCC, w: u32, h: u32) -> io::Result<Vec<(u32, u32)>> {
    let mut out = Vec::new();
    for iv in device.enum_frameintervals(fourcc, w, h)? {
        match iv.interval {
            FrameIntervalEnum::Discrete(f) => out.push((f.numerator, f.denominator)),
            FrameIntervalEnum::Stepwise(s) => {
                out.push((s.min.numerator, s.min.denominator));
                out.push((s.max.numerator, s.max.denominator));
            }
        }
    }
    // Some drivers list no intervals; treat the mode as usable at an unknown rate.
    if out.is_empty() {
        out.push((0, 0));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::looks_built_in;

    #[test]
    fn laptop_cameras_look_built_in_and_others_do_not() {
        for name in [
            "Integrated Camera",
            "FaceTime HD Camera",
            "usb-Chicony_Electronics_Co._Ltd._Integrated_Camera_0001-video-index0",
            "Built-in iSight",
        ] {
            assert!(looks_built_in(name), "{name}");
        }
        for name in [
            "Arducam OV9281 USB Camera",
            "usb-Intel_R__RealSense_TM_-video-index0",
            "HD Pro Webcam C920",
            "Logitech Webcam",
        ] {
            assert!(!looks_built_in(name), "{name}");
        }
    }
}
