//! `contrastxr calibrate`: lines the camera's background up with what each eye sees, while
//! the app runs. It switches running apps to `mode = background` through the config file (the
//! live `set` path: the layer reloads within a second), lets the user move and scale the
//! background picture of each eye in turn with keys, writes every nudge to the config at once
//! (`left_eye_offset`, `left_eye_scale`, `right_eye_offset`, `right_eye_scale`), and puts
//! `mode` back as it was at the end. On a terminal it reads single keys (raw mode); otherwise
//! one or more commands per line, so a script can drive it.

use super::args::{Args, Opt};
use super::error::{print, CliError};
use contrastxr::config::edit::{self, Table};
use contrastxr::config::{self, Env, Key, Value, EYES};
use std::io::{BufRead, Read};
use std::path::PathBuf;

pub const OPTIONS: &[Opt] = &[
    Opt::value("--app", "NAME"),
    Opt::value("--device", "SYSTEM"),
    Opt::value("--step", "F"),
];

mod latency;

pub fn usage() -> String {
    "usage: contrastxr calibrate [--app NAME | --device SYSTEM] [--step F]\n\n\
     Lines the camera's background up with what each eye sees, with the app running and the\n\
     headset on. Running apps show the background (mode background) until the end; for each\n\
     eye in turn (close the other one), move and scale the picture until its edges sit on the\n\
     real edges behind it. Every change is written to the config file at once (the app\n\
     follows within a second) as left_eye_offset/left_eye_scale and\n\
     right_eye_offset/right_eye_scale: at the file's top level, or with --app in\n\
     [app.\"NAME\"], with --device in [device.\"SYSTEM\"] (the headset's systemName, as the\n\
     layer logs it; `mode` is switched in the same table).\n\n\
     keys:   arrows or w a s d   move the picture up, left, down, right\n\
     \x20       + -                 bigger, smaller      ] [   wider, narrower\n\
     \x20       } {                 taller, shorter      > <   coarser, finer steps\n\
     \x20       r                   reset this eye       Enter next eye, then done\n\
     \x20       q                   cancel: put back what both eyes had\n\
     Then the latency: nod and turn the head, up/down (w s) raise/lower camera_latency_ms\n\
     until the background stops swimming against the world; Enter when done.\n\
     Without a terminal, stdin gives the same as words, any number per line: up down left\n\
     right bigger smaller wider narrower taller shorter coarser finer reset next quit\n\
     (end of input = done). --step F: the first move step, a fraction of the view (0.005).\n"
        .to_string()
}

/// One thing the user asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Action {
    /// Move the picture by this many steps (+x right, +y down).
    Move(f64, f64),
    /// Scale the picture by (1 + 2 step) to this power, per axis.
    Scale(f64, f64),
    Step(f64),
    Reset,
    Next,
    Quit,
}

fn word(w: &str) -> Option<Action> {
    use Action::*;
    Some(match w {
        "up" | "w" => Move(0.0, -1.0),
        "down" | "s" => Move(0.0, 1.0),
        "left" | "a" => Move(-1.0, 0.0),
        "right" | "d" => Move(1.0, 0.0),
        "bigger" | "+" | "=" => Scale(1.0, 1.0),
        "smaller" | "-" => Scale(-1.0, -1.0),
        "wider" | "]" => Scale(1.0, 0.0),
        "narrower" | "[" => Scale(-1.0, 0.0),
        "taller" | "}" => Scale(0.0, 1.0),
        "shorter" | "{" => Scale(0.0, -1.0),
        "coarser" | ">" => Step(2.0),
        "finer" | "<" => Step(0.5),
        "reset" | "r" => Reset,
        "next" | "done" => Next,
        "quit" | "q" => Quit,
        _ => return None,
    })
}

/// The actions in raw key bytes: arrows are ESC [ A..D; Enter and space go on; Ctrl-C quits.
fn keys(bytes: &[u8]) -> Vec<Action> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let arrow = (bytes[i] == 0x1b && bytes.get(i + 1) == Some(&b'['))
            .then(|| bytes.get(i + 2))
            .flatten();
        let action = match (arrow, bytes[i]) {
            (Some(b'A'), _) => Some(Action::Move(0.0, -1.0)),
            (Some(b'B'), _) => Some(Action::Move(0.0, 1.0)),
            (Some(b'C'), _) => Some(Action::Move(1.0, 0.0)),
            (Some(b'D'), _) => Some(Action::Move(-1.0, 0.0)),
            (_, b'\r' | b'\n' | b' ') => Some(Action::Next),
            (_, 3) => Some(Action::Quit),
            (_, b) => word(&char::from(b).to_string()),
        };
        i += if arrow.is_some() { 3 } else { 1 };
        out.extend(action);
    }
    out
}

/// Where the user's keys come from.
enum Input {
    /// The terminal stays in raw mode while this lives.
    Tty {
        _raw: RawTerminal,
    },
    Lines(std::io::StdinLock<'static>),
}

impl Input {
    fn open() -> Input {
        match RawTerminal::enter() {
            Some(raw) => Input::Tty { _raw: raw },
            None => Input::Lines(std::io::stdin().lock()),
        }
    }

    /// The next actions; None at the end of input.
    fn next(&mut self) -> Option<Result<Vec<Action>, String>> {
        match self {
            Input::Tty { .. } => {
                let mut buf = [0u8; 16];
                match std::io::stdin().read(&mut buf) {
                    Ok(0) | Err(_) => None,
                    Ok(n) => Some(Ok(keys(&buf[..n]))),
                }
            }
            Input::Lines(lines) => {
                let mut line = String::new();
                match lines.read_line(&mut line) {
                    Ok(0) | Err(_) => None,
                    Ok(_) => Some(
                        line.split_whitespace()
                            .map(|w| word(w).ok_or_else(|| format!("unknown command {w:?}")))
                            .collect(),
                    ),
                }
            }
        }
    }

    fn is_tty(&self) -> bool {
        matches!(self, Input::Tty { .. })
    }
}

/// The terminal in raw mode (no line buffering, no echo, Ctrl-C as a key) until dropped.
struct RawTerminal {
    saved: libc::termios,
}

impl RawTerminal {
    fn enter() -> Option<RawTerminal> {
        // SAFETY: isatty only inspects file descriptor 0.
        if unsafe { libc::isatty(0) } != 1 {
            return None;
        }
        // SAFETY: an all-zero termios is a valid out struct for tcgetattr.
        let mut saved: libc::termios = unsafe { std::mem::zeroed() };
        // SAFETY: fd 0 is a terminal (checked above); saved is a valid out pointer.
        if unsafe { libc::tcgetattr(0, &mut saved) } != 0 {
            return None;
        }
        let mut raw = saved;
        raw.c_lflag &= !(libc::ICANON | libc::ECHO | libc::ISIG);
        raw.c_cc[libc::VMIN] = 1;
        raw.c_cc[libc::VTIME] = 0;
        // SAFETY: as above, with a termios derived from the terminal's own.
        (unsafe { libc::tcsetattr(0, libc::TCSANOW, &raw) } == 0).then_some(RawTerminal { saved })
    }
}

impl Drop for RawTerminal {
    fn drop(&mut self) {
        // SAFETY: restores the settings read from the same terminal in `enter`.
        unsafe { libc::tcsetattr(0, libc::TCSANOW, &self.saved) };
    }
}

/// One eye's correction, as the config keys hold it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Eye {
    offset: [f64; 2],
    scale: [f64; 2],
}

impl Eye {
    const NONE: Eye = Eye {
        offset: [0.0, 0.0],
        scale: [1.0, 1.0],
    };

    fn apply(&mut self, action: Action, step: f64) {
        // Values are kept to 5 decimals so the file stays readable.
        let round = |x: f64| (x * 1e5).round() / 1e5;
        match action {
            Action::Move(dx, dy) => {
                self.offset = [
                    round(self.offset[0] + dx * step),
                    round(self.offset[1] + dy * step),
                ];
            }
            Action::Scale(px, py) => {
                let f = 1.0 + 2.0 * step;
                self.scale = [
                    round(self.scale[0] * f.powf(px)),
                    round(self.scale[1] * f.powf(py)),
                ];
            }
            Action::Reset => *self = Eye::NONE,
            _ => {}
        }
    }
}

/// The config file being edited, and the table the calibration goes to.
struct Target {
    path: PathBuf,
    seed: Option<PathBuf>,
    app: Option<String>,
    device: Option<String>,
}

fn key(name: &str) -> &'static Key {
    config::key(name).expect("calibration keys are config keys")
}

/// An f32 from the config as the f64 that prints the same (0.01, not 0.009999999776).
fn short(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

fn pair(v: [f64; 2]) -> Value {
    Value::Pair(v.map(|x| x as f32))
}

impl Target {
    fn table(&self) -> Table<'_> {
        match (&self.app, &self.device) {
            (Some(app), _) => Table::App(app),
            (None, Some(device)) => Table::Device(device),
            (None, None) => Table::Top,
        }
    }

    fn set(&self, name: &str, value: &Value) -> Result<(), CliError> {
        let seed = self.seed.as_deref();
        edit::set_in(&self.path, seed, self.table(), key(name), value).map_err(CliError::Failure)
    }

    /// The eye's correction as the config gives it now.
    fn eye(&self, settings: &config::Settings, eye: usize) -> Eye {
        let r = &settings.registration;
        Eye {
            offset: r.eye_offset[eye].map(short),
            scale: r.eye_scale[eye].map(short),
        }
    }

    fn write_eye(&self, eye: usize, was: &Eye, now: &Eye) -> Result<(), CliError> {
        let name = EYES[eye];
        if now.offset != was.offset {
            self.set(&format!("{name}_eye_offset"), &pair(now.offset))?;
        }
        if now.scale != was.scale {
            self.set(&format!("{name}_eye_scale"), &pair(now.scale))?;
        }
        Ok(())
    }

    /// Puts `mode` back as the file had it (removed if it had none).
    fn restore_mode(&self, previous: &Option<Value>) -> Result<(), CliError> {
        match previous {
            Some(v) => self.set("mode", v),
            None => edit::unset(&self.path, self.table(), key("mode")).map_err(CliError::Failure),
        }
    }
}

fn say(input: &Input, line: &str) {
    // In raw mode the terminal does not return the carriage by itself.
    let end = if input.is_tty() { "\r\n" } else { "\n" };
    print(&format!("{line}{end}"));
}

fn describe(eye: usize, e: &Eye, step: f64) -> String {
    format!(
        "{} eye: offset [{}, {}], scale [{}, {}] (step {step})",
        EYES[eye], e.offset[0], e.offset[1], e.scale[0], e.scale[1]
    )
}

fn summary(eyes: &[Eye; 2]) -> String {
    let eye = |i: usize| {
        let e = &eyes[i];
        format!(
            "{n}_eye_offset = [{}, {}], {n}_eye_scale = [{}, {}]",
            e.offset[0],
            e.offset[1],
            e.scale[0],
            e.scale[1],
            n = EYES[i]
        )
    };
    format!("{}; {}", eye(0), eye(1))
}

/// How the procedure ended.
enum End {
    Done,
    Cancelled,
}

fn calibrate_eyes(
    target: &Target,
    input: &mut Input,
    eyes: &mut [Eye; 2],
    mut step: f64,
) -> Result<End, CliError> {
    let mut current = 0;
    say(input, &format!("{} eye: close the other eye, then move and scale the picture until it lies on the real edges behind it; Enter when done.", EYES[current]));
    say(input, &describe(current, &eyes[current], step));
    while let Some(actions) = input.next() {
        let actions = match actions {
            Ok(a) => a,
            Err(e) => {
                say(input, &format!("{e}; see contrastxr calibrate --help"));
                continue;
            }
        };
        for action in actions {
            match action {
                Action::Quit => return Ok(End::Cancelled),
                Action::Next if current == 1 => return Ok(End::Done),
                Action::Next => {
                    current = 1;
                    say(input, "right eye: close the left eye now; Enter when done.");
                }
                Action::Step(f) => step = (step * f).clamp(0.0005, 0.1),
                other => {
                    let was = eyes[current];
                    eyes[current].apply(other, step);
                    target.write_eye(current, &was, &eyes[current])?;
                }
            }
            say(input, &describe(current, &eyes[current], step));
        }
    }
    Ok(End::Done)
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let app = args.value(&["--app"])?;
    let device = args.value(&["--device"])?;
    let step = match args.value(&["--step"])? {
        Some(s) => short(super::args::parse_f32("--step", &s)?),
        None => 0.005,
    };
    args.finish()?;
    if !(0.0005..=0.1).contains(&step) {
        return Err(CliError::Failure(format!(
            "--step must be in [0.0005, 0.1], got {step}"
        )));
    }
    let (path, seed) = config::path::for_writing(&Env::capture()).map_err(CliError::Failure)?;
    if app.is_some() && device.is_some() {
        return Err(CliError::Usage("give --app or --device, not both".into()));
    }
    let target = Target {
        path,
        seed,
        app,
        device,
    };
    let previous = edit::entry(
        &target.path,
        target.seed.as_deref(),
        target.table(),
        key("mode"),
    )
    .map_err(CliError::Failure)?;
    for name in ["mode", "left_eye_offset", "right_eye_offset"] {
        if std::env::var_os(key(name).env).is_some() {
            eprintln!(
                "note: {} is set in this shell; an app started with it ignores the file's {name}",
                key(name).env
            );
        }
    }
    let who = config::Who {
        app: target.app.as_deref().unwrap_or(""),
        device: target.device.as_deref(),
    };
    let settings = edit::current(&target.path, target.seed.as_deref(), who);
    let start = [target.eye(&settings, 0), target.eye(&settings, 1)];
    let mut eyes = start;
    target.set("mode", &Value::Text("background".into()))?;
    print(&format!(
        "mode = \"background\" in {}: running apps now show the camera's background.\n",
        target.path.display()
    ));
    let mut input = Input::open();
    let latency_was = f64::from(settings.motion.camera_latency_ms);
    let mut latency = latency_was;
    let mut ended = calibrate_eyes(&target, &mut input, &mut eyes, step);
    if matches!(ended, Ok(End::Done)) {
        ended = latency::calibrate_latency(&target, &mut input, latency_was).map(|(end, ms)| {
            latency = ms;
            end
        });
    }
    drop(input);
    // Whatever happened, running apps go back to the mode they had.
    let restored = target.restore_mode(&previous);
    match ended? {
        End::Done => print(&format!(
            "saved in {}: {}; camera_latency_ms = {latency}\n",
            target.path.display(),
            summary(&eyes)
        )),
        End::Cancelled => {
            for eye in 0..2 {
                target.write_eye(eye, &eyes[eye], &start[eye])?;
            }
            if latency != latency_was {
                target.set("camera_latency_ms", &Value::Float(latency_was as f32))?;
            }
            print("cancelled: both eyes are back as they were.\n");
        }
    }
    restored
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_and_words_are_the_same_actions() {
        assert_eq!(
            keys(b"\x1b[A\x1b[Cw+]\r\x03"),
            vec![
                Action::Move(0.0, -1.0),
                Action::Move(1.0, 0.0),
                Action::Move(0.0, -1.0),
                Action::Scale(1.0, 1.0),
                Action::Scale(1.0, 0.0),
                Action::Next,
                Action::Quit
            ]
        );
        assert_eq!(word("narrower"), Some(Action::Scale(-1.0, 0.0)));
        assert_eq!(word("sideways"), None);
    }

    #[test]
    fn an_eye_moves_and_scales_in_steps() {
        let mut e = Eye::NONE;
        e.apply(Action::Move(1.0, 0.0), 0.005);
        e.apply(Action::Move(1.0, -1.0), 0.005);
        e.apply(Action::Scale(1.0, 0.0), 0.005);
        assert_eq!(e.offset, [0.01, -0.005]);
        assert_eq!(e.scale, [1.01, 1.0]);
        e.apply(Action::Reset, 0.005);
        assert_eq!(e, Eye::NONE);
    }
}
