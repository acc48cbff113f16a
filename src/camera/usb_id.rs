//! A USB device's id (`VID:PID`, as lsusb prints them): what a device profile names its camera
//! by (`camera_usb_ids`) and `v4l2:auto` looks for.

use std::fmt;

/// A USB device's vendor and product id.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct UsbId {
    pub vendor: u16,
    pub product: u16,
}

impl fmt::Display for UsbId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04x}:{:04x}", self.vendor, self.product)
    }
}

/// Four hex digits at most, with or without `0x` (sysfs writes `0c45`).
pub fn hex16(text: &str) -> Option<u16> {
    let t = text.trim();
    let t = t.strip_prefix("0x").unwrap_or(t);
    (!t.is_empty() && t.len() <= 4)
        .then(|| u16::from_str_radix(t, 16).ok())
        .flatten()
}

impl UsbId {
    /// `VID:PID` in hexadecimal (`0c45:636b`).
    pub fn parse(text: &str) -> Result<UsbId, String> {
        let bad = || {
            format!(
                "{:?} is not VID:PID (four hex digits each, like 0c45:636b)",
                text.trim()
            )
        };
        let (vendor, product) = text.split_once(':').ok_or_else(bad)?;
        Ok(UsbId {
            vendor: hex16(vendor).ok_or_else(bad)?,
            product: hex16(product).ok_or_else(bad)?,
        })
    }

    /// A comma-separated list of `VID:PID`; empty for none.
    pub fn parse_list(text: &str) -> Result<Vec<UsbId>, String> {
        text.split(',')
            .map(str::trim)
            .filter(|part| !part.is_empty())
            .map(UsbId::parse)
            .collect()
    }

    /// The list's text form: `0c45:636b,0c45:6368`.
    pub fn list_text(ids: &[UsbId]) -> String {
        ids.iter()
            .map(UsbId::to_string)
            .collect::<Vec<_>>()
            .join(",")
    }
}
