//! `v4l2:auto`: which camera to take. Capture nodes with a colour mode this module converts are
//! ranked: a camera the device profile names by its USB id (`camera_usb_ids`, the headset's own)
//! first; then a camera on USB (from sysfs) before one on the platform or PCI bus (a laptop's
//! own, facing the user); the card's name decides only where sysfs says nothing. The choice is
//! kept by its stable path, so a reopen after a loss takes the same camera, and is said once.

use super::choose::choose_mode;
use super::devices::{modes, probe, stable_paths, DeviceInfo};
use super::usb::{self, sysfs_root};
use crate::camera::log_sink::log;
use crate::camera::source::CaptureConfig;
use crate::camera::usb_id::UsbId;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

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
    let Some(name) = node_name(node) else {
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

/// The node's name in sysfs (`video2`), through any link to it.
fn node_name(node: &Path) -> Option<String> {
    let path = std::fs::canonicalize(node).ok()?;
    Some(path.file_name()?.to_string_lossy().into_owned())
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
    /// Its USB device's id, when it is on USB.
    pub usb_id: Option<UsbId>,
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
    super::devices::device_nodes(dir)
        .into_iter()
        .filter_map(|p| probe(&p).ok())
        .filter(|(_, info)| info.capture)
        .filter(|(device, _)| {
            modes(device).is_ok_and(|m| choose_mode(&m, cfg.width, cfg.height, cfg.fps).is_some())
        })
        .map(|(_, info)| Candidate {
            stable: stable_paths(dir, &info.path),
            bus: bus_of(&info.path),
            usb_id: node_name(&info.path).and_then(|n| usb::usb_id_of(&sysfs_root(), &n)),
            info,
        })
        .collect()
}

/// The first candidate with the first of the `preferred` ids that one has.
fn preferred_camera(found: &[Candidate], preferred: &[UsbId]) -> Option<(usize, UsbId)> {
    preferred.iter().find_map(|id| {
        let k = found.iter().position(|c| c.usb_id == Some(*id))?;
        Some((k, *id))
    })
}

/// The candidate to take, and why: a `preferred` one (the device profile's camera), else the
/// first that is not built in, else the first.
pub fn choose(found: &[Candidate], preferred: &[UsbId]) -> Option<(usize, String)> {
    if let Some((k, id)) = preferred_camera(found, preferred) {
        let why = format!("USB {id}, the camera camera_usb_ids names (the device profile's)");
        return Some((k, why));
    }
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
    let (k, why) = choose(&found, &cfg.usb_ids)?;
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

#[cfg(test)]
mod tests {
    use super::super::usb::fake;
    use super::*;

    const LUMA: UsbId = UsbId {
        vendor: 0x0c45,
        product: 0x636b,
    };
    const BEAST: UsbId = UsbId {
        vendor: 0x0c45,
        product: 0x6368,
    };

    fn candidate(node: &str, card: &str, bus: Bus, usb_id: Option<UsbId>) -> Candidate {
        Candidate {
            info: DeviceInfo {
                path: PathBuf::from("/dev").join(node),
                card: card.into(),
                driver: "uvcvideo".into(),
                bus: String::new(),
                capture: true,
            },
            stable: Vec::new(),
            bus,
            usb_id,
        }
    }

    /// A laptop's camera, a USB webcam, then the glasses' camera (ids from a fake sysfs).
    fn three(sys: &Path) -> Vec<Candidate> {
        let webcam = UsbId {
            vendor: 0x046d,
            product: 0x0825,
        };
        fake::node(sys, "video0", 1, None);
        fake::node(sys, "video2", 2, Some(webcam));
        fake::node(sys, "video4", 3, Some(LUMA));
        let found = [
            ("video0", "Integrated Camera", Bus::Internal),
            ("video2", "HD Webcam C270", Bus::Usb),
            ("video4", "VITURE Camera", Bus::Usb),
        ];
        found
            .into_iter()
            .map(|(node, card, bus)| candidate(node, card, bus, usb::usb_id_of(sys, node)))
            .collect()
    }

    #[test]
    fn the_profiles_camera_ranks_first() {
        let sys = fake::root("auto-preferred");
        let found = three(&sys);
        assert_eq!(found[2].usb_id, Some(LUMA));
        let (k, why) = choose(&found, &[BEAST, LUMA]).unwrap();
        assert_eq!(k, 2);
        assert!(why.starts_with("USB 0c45:636b, the camera"), "{why}");
        // Of two preferred ids present, the one listed first.
        let mut found = found;
        found[1].usb_id = Some(BEAST);
        assert_eq!(choose(&found, &[BEAST, LUMA]).unwrap().0, 1);
        assert_eq!(choose(&found, &[LUMA, BEAST]).unwrap().0, 2);
    }

    #[test]
    fn without_the_profiles_camera_the_choice_is_unchanged() {
        let sys = fake::root("auto-not-preferred");
        let found = three(&sys);
        let absent = UsbId {
            vendor: 0x35ca,
            product: 0x1201,
        };
        for preferred in [&[][..], &[absent][..]] {
            let (k, why) = choose(&found, preferred).unwrap();
            assert_eq!(k, 1, "{why}");
            assert!(why.contains("not built in (on USB)"), "{why}");
        }
        // A preferred camera wins even where it would count as built in.
        let built_in = [candidate(
            "video0",
            "Integrated Camera",
            Bus::Internal,
            Some(LUMA),
        )];
        assert_eq!(choose(&built_in, &[LUMA]).unwrap().0, 0);
        assert!(choose(&[], &[LUMA]).is_none());
    }
}
