//! The calibration's last step: the camera's latency. With motion compensation the background
//! stays on the world while the head moves only when the camera frame's capture time is right;
//! a camera whose timestamps are late makes the background swim against the world on every
//! nod. The user nods and turns the head and raises or lowers `camera_latency_ms` until it
//! stops; each change is written at once.

use super::{say, Action, CliError, End, Input, Target};
use contrastxr::config::Value;

fn describe(ms: f64, step: f64) -> String {
    format!("camera_latency_ms = {ms} (step {step} ms)")
}

/// Runs the step from `start` ms; returns how it ended and the latency then.
pub(super) fn calibrate_latency(
    target: &Target,
    input: &mut Input,
    start: f64,
) -> Result<(End, f64), CliError> {
    let (mut ms, mut step) = (start, 5.0);
    say(input, "latency: nod and turn your head; up/down (w/s) raise/lower camera_latency_ms until the background stops swimming against the world; Enter when done.");
    say(input, &describe(ms, step));
    while let Some(actions) = input.next() {
        let Ok(actions) = actions else {
            continue;
        };
        for action in actions {
            let was = ms;
            match action {
                Action::Quit => return Ok((End::Cancelled, ms)),
                Action::Next => return Ok((End::Done, ms)),
                Action::Move(_, dy) => ms = (ms - dy * step).max(0.0),
                Action::Step(f) => step = (step * f).clamp(1.0, 100.0),
                Action::Reset => ms = 0.0,
                Action::Scale(..) => {}
            }
            if ms != was {
                target.set("camera_latency_ms", &Value::Float(ms as f32))?;
            }
            say(input, &describe(ms, step));
        }
    }
    Ok((End::Done, ms))
}
