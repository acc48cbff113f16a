//! Camera controls that would otherwise drift: exposure, white balance and gain, fixed when the
//! config gives a value (each change of an automatic control becomes a change of tint), and
//! listed by `contrastxr camera list`.

use crate::camera::log::log;
use crate::camera::source::CameraControls;
use v4l::control::{Control, Value};
use v4l::Device;

// V4L2 control ids (linux/v4l2-controls.h).
const GAIN: u32 = 0x0098_0913;
const AUTOGAIN: u32 = 0x0098_0912;
const AUTO_WHITE_BALANCE: u32 = 0x0098_090c;
const WHITE_BALANCE_TEMPERATURE: u32 = 0x0098_091a;
const EXPOSURE_AUTO: u32 = 0x009a_0901;
const EXPOSURE_ABSOLUTE: u32 = 0x009a_0902;
/// V4L2_EXPOSURE_MANUAL in EXPOSURE_AUTO's menu.
const EXPOSURE_MANUAL: i64 = 1;
/// EXPOSURE_ABSOLUTE counts in units of 100 microseconds.
const EXPOSURE_UNIT_US: i64 = 100;

/// The value that turns an automatic control off.
#[derive(Clone, Copy)]
enum Off {
    Menu(i64),
    Flag(bool),
}

impl Off {
    fn value(self) -> Value {
        match self {
            Off::Menu(v) => Value::Integer(v),
            Off::Flag(b) => Value::Boolean(b),
        }
    }

    fn is(self, v: &Value) -> bool {
        match (self, v) {
            (Off::Menu(a), Value::Integer(b)) => a == *b,
            (Off::Flag(a), Value::Boolean(b)) => a == *b,
            _ => false,
        }
    }
}

/// One fixed control: the automatic switch to turn off (value when off), the value control,
/// its unit in the config's terms, and the config key.
struct Fixed {
    key: &'static str,
    auto: (u32, Off),
    value: u32,
    /// Config units per control unit.
    scale: i64,
    unit: &'static str,
}

const EXPOSURE: Fixed = Fixed {
    key: "camera_exposure",
    auto: (EXPOSURE_AUTO, Off::Menu(EXPOSURE_MANUAL)),
    value: EXPOSURE_ABSOLUTE,
    scale: EXPOSURE_UNIT_US,
    unit: "us",
};
const WHITE_BALANCE: Fixed = Fixed {
    key: "camera_white_balance",
    auto: (AUTO_WHITE_BALANCE, Off::Flag(false)),
    value: WHITE_BALANCE_TEMPERATURE,
    scale: 1,
    unit: "K",
};
const GAIN_FIXED: Fixed = Fixed {
    key: "camera_gain",
    auto: (AUTOGAIN, Off::Flag(false)),
    value: GAIN,
    scale: 1,
    unit: "",
};

/// Sets the controls the config fixes and logs, for each, the value the camera accepted.
pub fn apply(device: &Device, controls: &CameraControls, shown: &str) {
    for (fixed, wanted) in [
        (&EXPOSURE, controls.exposure_us),
        (&WHITE_BALANCE, controls.white_balance_k),
        (&GAIN_FIXED, controls.gain),
    ] {
        if let Some(wanted) = wanted {
            log(&format!(
                "{shown}: {}",
                set(device, fixed, i64::from(wanted))
            ));
        }
    }
}

/// Turns the automatic control off and sets the value; says what the camera took.
fn set(device: &Device, f: &Fixed, wanted: i64) -> String {
    if device.control(f.value).is_err() {
        return format!(
            "{} {wanted}{}: the camera has no such control",
            f.key, f.unit
        );
    }
    // Cameras without an automatic switch have nothing to turn off.
    let (auto, off) = f.auto;
    if device.control(auto).is_ok() {
        let _ = device.set_control(Control {
            id: auto,
            value: off.value(),
        });
    }
    let value = Value::Integer((wanted + f.scale / 2) / f.scale);
    let set = device.set_control(Control { id: f.value, value });
    match (set, device.control(f.value).map(|c| c.value)) {
        (Ok(()), Ok(Value::Integer(took))) => format!(
            "{} {wanted}{}: the camera took {}{}",
            f.key,
            f.unit,
            took * f.scale,
            f.unit
        ),
        (Err(e), _) | (_, Err(e)) => {
            format!("{} {wanted}{}: the camera refused it ({e})", f.key, f.unit)
        }
        (Ok(()), Ok(other)) => format!("{} {wanted}{}: the camera took {other:?}", f.key, f.unit),
    }
}

/// The camera's exposure, white balance and gain controls: range, default and value, in the
/// config's units (for `camera list`).
pub fn describe(device: &Device) -> Vec<String> {
    let Ok(all) = device.query_controls() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for f in [&EXPOSURE, &WHITE_BALANCE, &GAIN_FIXED] {
        let Some(d) = all.iter().find(|d| d.id == f.value) else {
            continue;
        };
        let now = match device.control(f.value).map(|c| c.value) {
            Ok(Value::Integer(v)) => (v * f.scale).to_string(),
            _ => "?".into(),
        };
        let auto = match device.control(f.auto.0).map(|c| c.value) {
            Ok(v) if f.auto.1.is(&v) => ", fixed",
            Ok(_) => ", automatic",
            Err(_) => "",
        };
        out.push(format!(
            "{} {}..{}{} (default {}, now {now}{auto})",
            f.key,
            d.minimum * f.scale,
            d.maximum * f.scale,
            f.unit,
            d.default * f.scale,
        ));
    }
    out
}
