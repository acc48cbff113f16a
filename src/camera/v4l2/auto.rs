//! `v4l2:auto`: which camera to take. Capture nodes with a colour mode this module converts are
//! ranked: a camera on USB (from sysfs) before one on the platform or PCI bus (a laptop's own,
//! facing the user); the card's name decides only where sysfs says nothing. The choice is kept
//! by its stable path, so a reopen after a loss takes the same camera, and is said once.

use super::{choose_mode, modes, probe, stable_paths, DeviceInfo};
use crate::camera::log::log;
use crate::camera::CaptureConfig;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Where sysfs is: `$CONTRASTXR_SYSFS_ROOT` (tests) or `/sys`.
fn sysfs_root() -> PathBuf {
    std::env::var_os("CONTRASTXR_SYSFS_ROOT").map_or_else(|| PathBuf::from("/sys"), PathBuf::from)
}

/// The bus a camera hangs on, as sysfs tells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bus {
    Usb,
    /// Platform or PCI: part of the machine.
    Internal,
    Unknown,
}

/// `/sys/class/video4linux/videoN/device` resolves to a path through the USB tree for USB
/// cameras.
pub fn bus_of(node: &Path) -> Bus {
    let Some(name) = std::fs::canonicalize(node)
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_owned()))
    else {
        return Bus::Unknown;
    };
    let link = sysfs_root()
        .join("class/video4linux")
        .join(name)
        .join("device");
    match std::fs::canonicalize(&link) {
        Ok(p)
            if p.components()
                .any(|c| c.as_os_str().to_string_lossy().starts_with("usb")) =>
        {
            Bus::Usb
        }
        Ok(_) => Bus::Internal,
        Err(_) => Bus::Unknown,
    }
}

/// Words in a camera's name that mark a laptop's or monitor's own camera (used only when sysfs
/// does not tell the bus). "Webcam" is not one: most USB cameras are called that.
const BUILT_IN_WORDS: [&str; 5] = [
    "integrated",
    "built-in",
    "builtin",
    "facetime",
    "user facing",
];

/// Whether a camera's name (its card, or a stable path's name) says it is built in.
pub fn looks_built_in(name: &str) -> bool {
    let name = name.to_lowercase().replace(['_', '-'], " ");
    BUILT_IN_WORDS
        .iter()
        .any(|w| name.contains(&w.replace('-', " ")))
}

/// One capture node `v4l2:auto` may take.
pub struct Candidate {
    pub info: DeviceInfo,
    /// Its stable paths (by-id first), which keep naming it across renumbering.
    pub stable: Vec<PathBuf>,
    pub bus: Bus,
}

impl Candidate {
    fn built_in(&self) -> bool {
        match self.bus {
            Bus::Usb => false,
            Bus::Internal => true,
            Bus::Unknown => {
                looks_built_in(&self.info.card)
                    || self
                        .stable
                        .iter()
                        .any(|p| looks_built_in(&p.to_string_lossy()))
            }
        }
    }

    /// The path the choice is kept by.
    fn keep_path(&self) -> PathBuf {
        self.stable.first().unwrap_or(&self.info.path).clone()
    }
}

/// The capture nodes of `dir` with a mode `cfg` can use, in node order.
pub fn candidates(dir: &Path, cfg: &CaptureConfig) -> Vec<Candidate> {
    super::device_nodes(dir)
        .into_iter()
        .filter_map(|p| probe(&p).ok())
        .filter(|(_, info)| info.capture)
        .filter(|(device, _)| {
            modes(device).is_ok_and(|m| choose_mode(&m, cfg.width, cfg.height, cfg.fps).is_some())
        })
        .map(|(_, info)| Candidate {
            stable: stable_paths(dir, &info.path),
            bus: bus_of(&info.path),
            info,
        })
        .collect()
}

/// The candidate to take, and why: the first that is not built in, else the first. (A list of
/// preferred cameras would rank before this.)
pub fn choose(found: &[Candidate]) -> Option<(usize, String)> {
    let chosen = found.iter().position(|c| !c.built_in());
    let why = |c: &Candidate| match c.bus {
        Bus::Usb => "on USB",
        Bus::Internal => "not built in",
        Bus::Unknown => "its name does not say built in",
    };
    Some(match chosen {
        Some(k) if found.len() == 1 => (
            k,
            format!("the only usable capture device, {}", why(&found[k])),
        ),
        Some(k) => (
            k,
            format!(
                "the first of {} usable capture devices that is not built in ({})",
                found.len(),
                why(&found[k])
            ),
        ),
        None if found.is_empty() => return None,
        None => (
            0,
            "every usable capture device looks built in: the first".into(),
        ),
    })
}

/// The camera `v4l2:auto` takes in `dir`, by its stable path: the one taken before in this
/// process while it is still there, else a new choice, said once.
pub fn resolve(dir: &Path, cfg: &CaptureConfig) -> Option<PathBuf> {
    static KEPT: Mutex<Option<PathBuf>> = Mutex::new(None);
    let mut kept = KEPT.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(path) = kept.as_ref().filter(|p| p.exists()) {
        return Some(path.clone());
    }
    let found = candidates(dir, cfg);
    let (k, why) = choose(&found)?;
    let c = &found[k];
    let path = c.keep_path();
    log(&format!(
        "v4l2:auto took {} ({}): {why}",
        path.display(),
        c.info.card
    ));
    *kept = Some(path.clone());
    Some(path)
}
