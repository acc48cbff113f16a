//! Camera controls that would otherwise drift: exposure, white balance and gain, fixed when the
//! config gives a value (each change of an automatic control becomes a change of tint), and
//! listed by `contrastxr camera list`.

use crate::camera::log_sink::log;
use crate::camera::source::CameraControls;
use v4l::control::{Control, Description, Value};
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
/// V4L2_EXPOSURE_AUTO and V4L2_EXPOSURE_APERTURE_PRIORITY: the automatic modes.
const EXPOSURE_FULL_AUTO: i64 = 0;
const EXPOSURE_APERTURE_PRIORITY: i64 = 3;
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

/// What the camera's controls were before the layer changed them, put back at close so that
/// other programs find the camera as it was.
#[derive(Default)]
pub struct Saved(Vec<Control>);

/// Sets the controls the config fixes, turns the automatic control back on for those it leaves
/// to the camera, and logs, for each change, what the camera took. Returns the values the
/// changed controls had before.
pub fn apply(device: &Device, controls: &CameraControls, shown: &str) -> Saved {
    let mut saved = Saved::default();
    for (fixed, wanted) in [
        (&EXPOSURE, controls.exposure_us),
        (&WHITE_BALANCE, controls.white_balance_k),
        (&GAIN_FIXED, controls.gain),
    ] {
        let said = match wanted {
            Some(wanted) => set(device, fixed, i64::from(wanted), &mut saved),
            None => automatic(device, fixed, &mut saved),
        };
        if let Some(said) = said {
            log(&format!("{shown}: {said}"));
        }
    }
    saved
}

/// Puts back the values read before the layer changed them: the value while the automatic
/// control is off, then the automatic control itself.
pub fn restore(device: &Device, saved: Saved) {
    for c in saved.0.into_iter().rev() {
        let _ = device.set_control(c);
    }
}

/// Remembers a control's value before the first change to it.
fn remember(device: &Device, id: u32, saved: &mut Saved) {
    if saved.0.iter().all(|c| c.id != id) {
        if let Ok(c) = device.control(id) {
            saved.0.push(c);
        }
    }
}

/// Turns a control left to the camera back to automatic if something had fixed it.
fn automatic(device: &Device, f: &Fixed, saved: &mut Saved) -> Option<String> {
    let (id, off) = f.auto;
    let now = device.control(id).ok()?.value;
    if !off.is(&now) {
        return None;
    }
    let on = match off {
        Off::Flag(b) => Value::Boolean(!b),
        Off::Menu(manual) => {
            let default = description(device, id).map(|d| d.default);
            // The camera's own default, unless that is manual: aperture priority, else auto.
            Value::Integer(match default {
                Some(d) if d != manual => d,
                _ if menu_has(device, id, EXPOSURE_APERTURE_PRIORITY) => EXPOSURE_APERTURE_PRIORITY,
                _ => EXPOSURE_FULL_AUTO,
            })
        }
    };
    remember(device, id, saved);
    Some(match device.set_control(Control { id, value: on }) {
        Ok(()) => format!("{} auto: the camera's automatic control is on again", f.key),
        Err(e) => format!(
            "{} auto: the camera refused its automatic control ({e})",
            f.key
        ),
    })
}

fn description(device: &Device, id: u32) -> Option<Description> {
    device
        .query_controls()
        .ok()?
        .into_iter()
        .find(|d| d.id == id)
}

fn menu_has(device: &Device, id: u32, value: i64) -> bool {
    description(device, id).is_some_and(|d| (d.minimum..=d.maximum).contains(&value))
}

/// Turns the automatic control off and sets the value; says what the camera took, or why the
/// value was refused (outside the camera's range: nothing changes).
fn set(device: &Device, f: &Fixed, wanted: i64, saved: &mut Saved) -> Option<String> {
    let Some(d) = description(device, f.value) else {
        return Some(format!(
            "{} {wanted}{}: the camera has no such control",
            f.key, f.unit
        ));
    };
    let (low, high) = (d.minimum * f.scale, d.maximum * f.scale);
    if !(low..=high).contains(&wanted) {
        return Some(format!(
            "{} {wanted}{}: refused, outside the camera's range {low}..{high}{}",
            f.key, f.unit, f.unit
        ));
    }
    // Cameras without an automatic switch have nothing to turn off.
    let (auto, off) = f.auto;
    remember(device, auto, saved);
    remember(device, f.value, saved);
    if device.control(auto).is_ok() {
        let _ = device.set_control(Control {
            id: auto,
            value: off.value(),
        });
    }
    let value = Value::Integer(((wanted + f.scale / 2) / f.scale).clamp(d.minimum, d.maximum));
    let set = device.set_control(Control { id: f.value, value });
    Some(match (set, device.control(f.value).map(|c| c.value)) {
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
    })
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
