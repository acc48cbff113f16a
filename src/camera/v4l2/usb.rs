//! USB ids (`VID:PID`, as lsusb prints them) of cameras, read from sysfs: what lets a device
//! profile name the camera built into a headset (`camera_usb_ids`), so that `v4l2:auto` takes
//! it and `contrastxr doctor` can say whether it is connected. Sysfs is `/sys`, or
//! `$CONTRASTXR_SYSFS_ROOT` (tests).

use crate::camera::usb_id::{hex16, UsbId};
use std::path::{Path, PathBuf};

/// Where sysfs is: `$CONTRASTXR_SYSFS_ROOT` (tests) or `/sys`.
pub fn sysfs_root() -> PathBuf {
    std::env::var_os("CONTRASTXR_SYSFS_ROOT").map_or_else(|| PathBuf::from("/sys"), PathBuf::from)
}

/// The USB id of the device video node `name` (`video2`) belongs to: the `idVendor` and
/// `idProduct` of the first folder above its sysfs device (a UVC interface) that has them.
pub fn usb_id_of(sysfs: &Path, name: &str) -> Option<UsbId> {
    let link = sysfs.join("class/video4linux").join(name).join("device");
    let device = std::fs::canonicalize(link).ok()?;
    let read = |dir: &Path, file: &str| {
        std::fs::read_to_string(dir.join(file))
            .ok()
            .and_then(|t| hex16(&t))
    };
    device.ancestors().find_map(|dir| {
        Some(UsbId {
            vendor: read(dir, "idVendor")?,
            product: read(dir, "idProduct")?,
        })
    })
}

/// Every video4linux node on USB with its device's id, in node order (video2 before video10).
pub fn usb_video_nodes(sysfs: &Path) -> Vec<(String, UsbId)> {
    let dir = sysfs.join("class/video4linux");
    let mut found: Vec<(u64, String, UsbId)> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let number = name.strip_prefix("video")?.parse().ok()?;
            let id = usb_id_of(sysfs, &name)?;
            Some((number, name, id))
        })
        .collect();
    found.sort();
    found.into_iter().map(|(_, name, id)| (name, id)).collect()
}

/// A fake sysfs for tests: video nodes hanging off USB devices.
#[cfg(test)]
pub mod fake {
    use super::UsbId;
    use std::path::Path;

    /// A fresh folder for one test, removed with the guard.
    pub fn root(name: &str) -> crate::scratch::ScratchDir {
        crate::scratch::ScratchDir::new(&format!("sysfs-{name}"))
    }

    /// `class/video4linux/NODE/device` -> `devices/.../usb1/1-PORT/1-PORT:1.0`, with the USB
    /// device's `idVendor` and `idProduct` in `1-PORT` (None: a node on the platform bus).
    pub fn node(sysfs: &Path, node: &str, port: u32, id: Option<UsbId>) {
        let device = match id {
            Some(id) => {
                let usb = sysfs.join(format!("devices/pci0000:00/usb1/1-{port}"));
                std::fs::create_dir_all(&usb).unwrap();
                std::fs::write(usb.join("idVendor"), format!("{:04x}\n", id.vendor)).unwrap();
                std::fs::write(usb.join("idProduct"), format!("{:04x}\n", id.product)).unwrap();
                usb.join(format!("1-{port}:1.0"))
            }
            None => sysfs.join(format!("devices/platform/camera{port}")),
        };
        std::fs::create_dir_all(&device).unwrap();
        let class = sysfs.join("class/video4linux").join(node);
        std::fs::create_dir_all(&class).unwrap();
        std::os::unix::fs::symlink(&device, class.join("device")).unwrap();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LUMA: UsbId = UsbId {
        vendor: 0x0c45,
        product: 0x636b,
    };

    #[test]
    fn ids_parse_as_lsusb_prints_them() {
        assert_eq!(UsbId::parse("0c45:636b"), Ok(LUMA));
        assert_eq!(UsbId::parse(" 0x0C45:0x636B "), Ok(LUMA));
        for bad in [
            "0c45",
            "0c45:",
            "0c45:636bb",
            "zz45:636b",
            ":636b",
            "0c45-636b",
        ] {
            assert!(UsbId::parse(bad).is_err(), "{bad}");
        }
        let list = UsbId::parse_list("0c45:636b, 0c45:6368,").unwrap();
        assert_eq!(UsbId::list_text(&list), "0c45:636b,0c45:6368");
        assert_eq!(UsbId::parse_list(""), Ok(Vec::new()));
        assert!(UsbId::parse_list("0c45:636b,webcam").is_err());
    }

    #[test]
    fn a_nodes_id_is_its_usb_devices() {
        let sys = fake::root("usb-ids");
        let other = UsbId {
            vendor: 0x046d,
            product: 0x0825,
        };
        fake::node(&sys, "video10", 3, Some(LUMA));
        fake::node(&sys, "video2", 2, Some(other));
        fake::node(&sys, "video0", 1, None);
        assert_eq!(usb_id_of(&sys, "video10"), Some(LUMA));
        assert_eq!(usb_id_of(&sys, "video0"), None);
        assert_eq!(usb_id_of(&sys, "video5"), None);
        assert_eq!(
            usb_video_nodes(&sys),
            [("video2".to_string(), other), ("video10".to_string(), LUMA)]
        );
    }
}
