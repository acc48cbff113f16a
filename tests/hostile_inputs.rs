//! Every path a user gives the layer or the tool is read within bounds: each setting that names
//! a file or folder, given each hostile input (a FIFO, device nodes, a folder, link loops, a
//! dangling link, an unreadable file, pictures declaring 40000x40000 pixels, a truncated file, a
//! 200 MiB file, a non-UTF-8 path). Through the real app path (the XR client on the real Monado
//! runtime, all cases against one service): the app reaches its frames and ends them all, the
//! layer says why in one line naming the path, soon after the app started, and the app's peak
//! resident memory stays within 64 MiB of a run with a valid background. Through the tool: the
//! same inputs give exit status 1 and the same words, within a second.

mod common;

use common::{sandbox, scratch_dir, CLI, XR_CLIENT};
use std::ffi::{OsStr, OsString};
use std::os::unix::ffi::OsStringExt;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// A hostile input: its name, and why a reader meaning a file refuses it (None: the words
/// depend on the reader, only the path is checked).
struct Input {
    name: &'static str,
    why: Option<&'static str>,
}

const INPUTS: &[Input] = &[
    Input {
        name: "fifo",
        why: Some("is a FIFO, not a file"),
    },
    Input {
        name: "dev-zero",
        why: Some("is a character device, not a file"),
    },
    Input {
        name: "dev-null",
        why: Some("is a character device, not a file"),
    },
    Input {
        name: "dev-urandom",
        why: Some("is a character device, not a file"),
    },
    Input {
        name: "folder",
        why: Some("is a folder, not a file"),
    },
    Input {
        name: "link-loop",
        why: Some("is a loop of symbolic links"),
    },
    Input {
        name: "dangling-link",
        why: Some("is a link to nothing"),
    },
    // Root (the sandbox's user) reads it anyway: then its content (text) is refused.
    Input {
        name: "unreadable",
        why: None,
    },
    Input {
        name: "png-40000",
        why: None,
    },
    Input {
        name: "jpeg-40000",
        why: None,
    },
    Input {
        name: "truncated",
        why: None,
    },
    Input {
        name: "200-mib",
        why: None,
    },
    Input {
        name: "non-utf8-path",
        why: None,
    },
];

/// A small valid PNG's bytes.
fn small_png() -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 16, 16);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&[200u8; 16 * 16 * 3]).unwrap();
    writer.finish().unwrap();
    bytes
}

/// A PNG whose header declares 40000x40000 pixels (and no pixel data).
fn png_40000() -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 40000, 40000);
    encoder.set_color(png::ColorType::Rgba);
    let writer = encoder.write_header().unwrap();
    drop(writer);
    bytes
}

/// A small JPEG whose frame header is patched to declare 40000x40000 pixels.
fn jpeg_40000() -> Vec<u8> {
    let mut bytes = Vec::new();
    let encoder = jpeg_encoder::Encoder::new(&mut bytes, 90);
    encoder
        .encode(&[90u8; 8 * 8 * 3], 8, 8, jpeg_encoder::ColorType::Rgb)
        .unwrap();
    let sof = bytes
        .windows(2)
        .position(|w| w == [0xFF, 0xC0])
        .expect("a baseline frame header");
    // FFC0, length (2), precision (1), then height and width (2 each).
    bytes[sof + 5..sof + 9].copy_from_slice(&[0x9C, 0x40, 0x9C, 0x40]);
    bytes
}

fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().expect("mkfifo");
    assert!(status.success());
}

/// Creates input `name` at `at` (or returns the device it names).
fn make(name: &str, at: &Path) -> PathBuf {
    let link = |target: &Path| std::os::unix::fs::symlink(target, at).unwrap();
    match name {
        "fifo" => mkfifo(at),
        "dev-zero" => link(Path::new("/dev/zero")),
        "dev-null" => link(Path::new("/dev/null")),
        "dev-urandom" => link(Path::new("/dev/urandom")),
        "folder" => std::fs::create_dir_all(at).unwrap(),
        "link-loop" => link(at),
        "dangling-link" => link(&at.with_extension("nowhere")),
        "unreadable" => {
            std::fs::write(at, "not for anyone's eyes\n").unwrap();
            std::fs::set_permissions(at, std::os::unix::fs::PermissionsExt::from_mode(0o000))
                .unwrap();
        }
        "png-40000" => std::fs::write(at, png_40000()).unwrap(),
        "jpeg-40000" => std::fs::write(at, jpeg_40000()).unwrap(),
        "truncated" => std::fs::write(at, &small_png()[..60]).unwrap(),
        "200-mib" => std::fs::File::create(at)
            .unwrap()
            .set_len(200 << 20)
            .unwrap(),
        "non-utf8-path" => {
            let mut raw = at.as_os_str().to_owned().into_vec();
            raw.extend_from_slice(b"-caf\xe9");
            let odd = PathBuf::from(OsString::from_vec(raw));
            std::fs::write(&odd, small_png()).unwrap();
            return odd;
        }
        other => panic!("no input {other}"),
    }
    at.to_path_buf()
}

/// The words a reader meaning a file gives for `input` at `path`.
fn expected(input: &Input) -> Option<String> {
    input.why.map(String::from).or(match input.name {
        "png-40000" | "jpeg-40000" => {
            Some("declares 40000x40000 pixels, more than 16384x16384".into())
        }
        "200-mib" => Some("is 200 MiB, more than".into()),
        _ => None,
    })
}

// ---- the tool ----

/// What a reader of `kind` says of `input`: the words wanted in its line (None: only that it
/// refuses), or Ok when the input is valid for it.
#[derive(Debug)]
enum Outcome {
    Refused(Option<String>),
    Ok,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Image,
    Text,
    Folder,
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

fn outcome(kind: Kind, input: &Input) -> Outcome {
    let words = |w: &str| Outcome::Refused(Some(w.to_string()));
    match (kind, input.name) {
        // Root reads any file: then the text inside is what is refused.
        (Kind::Image | Kind::Text, "unreadable") if !is_root() => {
            words("cannot be read (permission denied)")
        }
        (Kind::Image, "unreadable") => words("is not a readable PNG or JPEG image"),
        (Kind::Image, "truncated") => words("is not a readable PNG"),
        (Kind::Text, "unreadable") => words("not valid TOML"),
        // The tool's arguments and the layer's variables are UTF-8 text, as the config is.
        (_, "non-utf8-path") => words("is not UTF-8 text"),
        (Kind::Image, _) => Outcome::Refused(expected(input)),
        (Kind::Text, "png-40000" | "jpeg-40000" | "truncated") => words("is not UTF-8 text"),
        (Kind::Text, "200-mib") => words("is 200 MiB, more than 1 MiB"),
        (Kind::Text, _) => Outcome::Refused(input.why.map(String::from)),
        (Kind::Folder, "folder") => Outcome::Ok,
        (Kind::Folder, "unreadable" | "png-40000" | "jpeg-40000" | "truncated" | "200-mib") => {
            words("is a file, not a folder")
        }
        (Kind::Folder, _) => {
            Outcome::Refused(input.why.map(|w| w.replace("not a file", "not a folder")))
        }
    }
}

struct ToolRun {
    code: i32,
    stderr: String,
    took: Duration,
}

fn tool(args: &[&OsStr], env: &[(&str, &OsStr)], home: &Path) -> ToolRun {
    let start = Instant::now();
    let out = Command::new(CLI)
        .args(args)
        .env("HOME", home)
        .env("XDG_CONFIG_HOME", home.join("config"))
        .env("XDG_STATE_HOME", home.join("state"))
        .envs(env.iter().map(|(k, v)| (*k, *v)))
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run the tool");
    ToolRun {
        code: out.status.code().unwrap_or(-1),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        took: start.elapsed(),
    }
}

/// A command of the tool: what it is, what it reads there, its arguments and environment.
type ToolCase<'a> = (
    &'static str,
    Kind,
    Vec<&'a OsStr>,
    Vec<(&'static str, &'a OsStr)>,
);

/// Each command of the tool that reads what a user names, with `hostile` in that place.
fn tool_cases<'a>(hostile: &'a OsStr, valid: &'a OsStr, out: &'a OsStr) -> Vec<ToolCase<'a>> {
    let o = |s: &'static str| OsStr::new(s);
    let cpu = [o("--engine"), o("cpu")];
    vec![
        (
            "enhance --display",
            Kind::Image,
            [
                &[o("enhance")][..],
                &cpu,
                &[
                    o("--display"),
                    hostile,
                    o("--background"),
                    valid,
                    o("-o"),
                    out,
                ],
            ]
            .concat(),
            vec![],
        ),
        (
            "enhance --background",
            Kind::Image,
            [
                &[o("enhance")][..],
                &cpu,
                &[
                    o("--display"),
                    valid,
                    o("--background"),
                    hostile,
                    o("-o"),
                    out,
                ],
            ]
            .concat(),
            vec![],
        ),
        (
            "evaluate --background",
            Kind::Image,
            [
                &[o("evaluate")][..],
                &cpu,
                &[o("--display"), valid, o("--background"), hostile],
            ]
            .concat(),
            vec![],
        ),
        (
            "pan IMAGE",
            Kind::Image,
            vec![o("pan"), hostile, o("-o"), out],
            vec![],
        ),
        (
            "config check",
            Kind::Text,
            vec![o("config"), o("check"), hostile],
            vec![],
        ),
        (
            "calibrate",
            Kind::Text,
            vec![o("calibrate")],
            vec![("CONTRASTXR_CONFIG", hostile)],
        ),
        (
            "animate --captures",
            Kind::Folder,
            vec![o("animate"), o("--captures"), hostile, o("-o"), out],
            vec![],
        ),
    ]
}

#[test]
fn the_tool_refuses_every_hostile_input_at_once() {
    let dir = scratch_dir("hostile-tool");
    let home = dir.join("home");
    std::fs::create_dir_all(&home).unwrap();
    let valid = dir.join("valid.png");
    std::fs::write(&valid, small_png()).unwrap();
    let mut table = Vec::new();
    for input in INPUTS {
        let path = make(input.name, &dir.join(input.name));
        let out = dir.join(format!("out-{}", input.name));
        for (what, kind, args, env) in
            tool_cases(path.as_os_str(), valid.as_os_str(), out.as_os_str())
        {
            let run = tool(&args, &env, &home);
            let wanted = outcome(kind, input);
            table.push(format!(
                "{:<14} {:<22} exit {} in {:>4} ms",
                input.name,
                what,
                run.code,
                run.took.as_millis()
            ));
            let about = format!("{what} with {}: {}", input.name, run.stderr);
            assert!(
                run.took < Duration::from_secs(1),
                "{about} took {:?}",
                run.took
            );
            match (wanted, what) {
                // An empty folder holds no captures: refused, with its own words.
                (Outcome::Ok, "animate --captures") => assert_eq!(run.code, 1, "{about}"),
                (Outcome::Ok, _) => assert_eq!(run.code, 0, "{about}"),
                (Outcome::Refused(words), _) => {
                    assert_eq!(run.code, 1, "{about}");
                    if let Some(words) = words {
                        assert!(run.stderr.contains(&words), "wanted '{words}': {about}");
                    }
                }
            }
        }
    }
    eprintln!("{}", table.join("\n"));
}

// ---- the layer, inside a real app ----

/// A setting that names a file or folder, as the layer reads it.
struct Setting {
    name: &'static str,
    /// The variable set, and its value around the input's path.
    var: &'static str,
    prefix: &'static str,
    kind: Kind,
    /// The background is refused: frames pass through untouched. Otherwise they are enhanced
    /// (defaults, or no captures).
    passes_through: bool,
}

const SETTINGS: &[Setting] = &[
    Setting {
        name: "config",
        var: "CONTRASTXR_CONFIG",
        prefix: "",
        kind: Kind::Text,
        passes_through: false,
    },
    Setting {
        name: "devices",
        var: "CONTRASTXR_DEVICES",
        prefix: "",
        kind: Kind::Text,
        passes_through: false,
    },
    Setting {
        name: "image",
        var: "CONTRASTXR_BACKGROUND",
        prefix: "image:",
        kind: Kind::Image,
        passes_through: true,
    },
    Setting {
        name: "y4m",
        var: "CONTRASTXR_BACKGROUND",
        prefix: "video:",
        kind: Kind::Image,
        passes_through: true,
    },
    Setting {
        name: "video-folder",
        var: "CONTRASTXR_BACKGROUND",
        prefix: "video:",
        kind: Kind::Image,
        passes_through: true,
    },
    Setting {
        name: "world",
        var: "CONTRASTXR_BACKGROUND",
        prefix: "world:",
        kind: Kind::Image,
        passes_through: true,
    },
    Setting {
        name: "capture",
        var: "CONTRASTXR_CAPTURE_DIR",
        prefix: "",
        kind: Kind::Folder,
        passes_through: false,
    },
];

/// What the layer says of `input` given to `setting`: the words in its line besides the path.
fn layer_outcome(setting: &Setting, input: &Input) -> Outcome {
    let words = |w: &str| Outcome::Refused(Some(w.to_string()));
    match (setting.name, input.name) {
        // A valid frame under a non-UTF-8 name is read like any other.
        ("video-folder", "non-utf8-path") => Outcome::Ok,
        ("video-folder", "unreadable") if is_root() => words("is not a readable PNG"),
        (_, "non-utf8-path") => words(&format!("{} is not UTF-8 text", setting.var)),
        ("y4m", "folder") => words("holds no PNG frames"),
        ("y4m", "200-mib") => words("has no Y4M header line"),
        ("y4m", "unreadable") if !is_root() => words("cannot be read (permission denied)"),
        ("y4m", _) if input.why.is_none() => words("is not a usable Y4M file"),
        _ => outcome(setting.kind, input),
    }
}

/// One case of the matrix: where its files go and the value of its setting.
struct Case<'a> {
    setting: &'a Setting,
    input: &'a Input,
    dir: PathBuf,
    value: OsString,
    /// The path the layer's line must name.
    named: PathBuf,
}

fn prepare_case<'a>(root: &Path, setting: &'a Setting, input: &'a Input) -> Case<'a> {
    let dir = root.join(format!("{}-{}", setting.name, input.name));
    std::fs::create_dir_all(&dir).unwrap();
    let named = if setting.name == "video-folder" {
        let frames = dir.join("frames");
        std::fs::create_dir_all(&frames).unwrap();
        if input.name == "non-utf8-path" {
            make(input.name, &frames.join("0001"));
            std::fs::rename(
                std::fs::read_dir(&frames)
                    .unwrap()
                    .next()
                    .unwrap()
                    .unwrap()
                    .path(),
                frames.join(OsString::from_vec(b"0001-caf\xe9.png".to_vec())),
            )
            .unwrap();
            frames
        } else {
            make(input.name, &frames.join("0001.png"))
        }
    } else {
        make(input.name, &dir.join("input"))
    };
    let target = if setting.name == "video-folder" {
        dir.join("frames")
    } else {
        named.clone()
    };
    let mut value = OsString::from(setting.prefix);
    value.push(target.as_os_str());
    Case {
        setting,
        input,
        dir,
        value,
        named,
    }
}

/// A bash word for `bytes`: $'...' with every byte escaped, so any path survives.
fn bash_word(bytes: &[u8]) -> String {
    let escaped: String = bytes.iter().map(|b| format!("\\x{b:02x}")).collect();
    format!("$'{escaped}'")
}

const FRAMES: &str = "12";

/// The script that runs every case against one Monado service: the client in the
/// background, its peak resident memory (VmHWM) read while it runs, its exit status.
fn matrix_script(
    root: &Path,
    base_config: &Path,
    cases: &[(String, Vec<(&str, OsString)>)],
) -> String {
    let mut s = String::from("#!/bin/bash\nrun_case() {\n  local dir=\"$1\"; shift\n  mkdir -p \"$dir/state\"\n  XDG_STATE_HOME=\"$dir/state\" \"$@\" >\"$dir/stdout\" 2>\"$dir/stderr\" </dev/null &\n  local pid=$! hwm=0 k v rest waited=0\n  while kill -0 $pid 2>/dev/null; do\n    while read -r k v rest; do [ \"$k\" = VmHWM: ] && hwm=$v; done <\"/proc/$pid/status\" 2>/dev/null\n    sleep 0.05; waited=$((waited + 1))\n    [ $waited -gt 1200 ] && kill -9 $pid\n  done\n  wait $pid; echo $? >\"$dir/rc\"; echo $hwm >\"$dir/hwm_kb\"\n}\n");
    let client = [
        XR_CLIENT,
        "--json",
        "--check-untouched",
        "--frames",
        FRAMES,
        "--size",
        "64x48",
    ]
    .join(" ");
    for (dir, env) in cases {
        let mut line = format!("run_case {} env CONTRASTXR=1 CONTRASTXR_FORCE=1 CONTRASTXR_INDICATOR=0 CONTRASTXR_PIPELINES=wait CONTRASTXR_BACKGROUND=color:#e0d020 CONTRASTXR_CONFIG={}", bash_word(dir.as_bytes()), bash_word(base_config.as_os_str().as_encoded_bytes()));
        for (var, value) in env {
            line.push_str(&format!(" {var}={}", bash_word(value.as_encoded_bytes())));
        }
        line.push_str(&format!(" {client}\n"));
        s.push_str(&line);
    }
    let _ = root;
    s
}

/// A case's results, read back from its folder.
struct CaseRun {
    rc: i32,
    hwm_kb: u64,
    report: Option<serde_json::Value>,
    lines: Vec<String>,
    log: String,
}

fn read_case(dir: &Path) -> CaseRun {
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap_or_default();
    let stdout = read("stdout");
    CaseRun {
        rc: read("rc").trim().parse().unwrap_or(-1),
        hwm_kb: read("hwm_kb").trim().parse().unwrap_or(0),
        report: stdout
            .lines()
            .rev()
            .filter(|l| l.starts_with("{\"ok\""))
            .find_map(|l| serde_json::from_str(l).ok()),
        lines: read("stderr")
            .lines()
            .filter_map(|l| l.strip_prefix("contrastxr: "))
            .map(String::from)
            .collect(),
        log: read("state/contrastxr/layer.log"),
    }
}

/// Seconds since midnight of a log line's RFC 3339 stamp (`2026-11-26T15:04:05.123Z ...`).
fn stamp_s(line: &str) -> Option<f64> {
    let time = line.get(11..23)?;
    let mut parts = time.split(':');
    let h: f64 = parts.next()?.parse().ok()?;
    let m: f64 = parts.next()?.parse().ok()?;
    let s: f64 = parts.next()?.parse().ok()?;
    Some(h * 3600.0 + m * 60.0 + s)
}

/// Seconds to the first log line containing `to` from the last of the layer's milestones
/// before it: its first line, the session's first line, the first frame it processes. What
/// lies between them is not the layer's reading of the input: the runtime's own start-up
/// (Monado's instance and system, up to 0.9 s on a loaded machine), and the pipeline build
/// before the first frame (`pipelines = "wait"`; 1.6 s under load), after which a capture
/// folder is first used.
fn seconds_to_line(log: &str, to: &str) -> Option<f64> {
    let lines: Vec<&str> = log.lines().collect();
    let at = lines.iter().position(|l| l.contains(to))?;
    let from = lines[..at]
        .iter()
        .rev()
        .find(|l| MILESTONES.iter().any(|m| l.contains(m)))?;
    Some(stamp_s(lines[at])? - stamp_s(from)?)
}

/// The layer's milestones, from the last of which its refusals are timed: its first line in a
/// process (at the app's xrCreateInstance), its first of a session (at xrCreateSession), and
/// its first processed frame.
const MILESTONES: [&str; 3] = ["layer loaded into", "] session on ", "] processing frames"];

#[test]
fn every_hostile_input_to_the_layer_is_refused_in_one_line_while_the_app_runs() {
    let Some(sandbox) = sandbox() else { return };
    let root = scratch_dir("hostile-layer");
    let base_config = root.join("base.toml");
    // A camera profile, so that `world:` is usable when its panorama is.
    std::fs::write(
        &base_config,
        "camera_fov = [100, 80]\nscene_distance = 10000\n",
    )
    .unwrap();
    let valid = root.join("valid.png");
    std::fs::write(&valid, small_png()).unwrap();
    let only = std::env::var("CONTRASTXR_HOSTILE_ONLY").unwrap_or_default();
    let mut cases = Vec::new();
    for setting in SETTINGS
        .iter()
        .filter(|s| only.is_empty() || only.split(',').any(|o| o == s.name))
    {
        for input in INPUTS {
            cases.push(prepare_case(&root, setting, input));
        }
    }
    let baseline_dir = root.join("baseline");
    let mut script_cases = vec![(
        baseline_dir.to_string_lossy().into_owned(),
        vec![(
            "CONTRASTXR_BACKGROUND",
            OsString::from(format!("image:{}", valid.display())),
        )],
    )];
    for c in &cases {
        let mut env = vec![(c.setting.var, c.value.clone())];
        if c.setting.name == "capture" {
            env.push(("CONTRASTXR_CAPTURE_FRAMES", OsString::from("3")));
        }
        script_cases.push((c.dir.to_string_lossy().into_owned(), env));
    }
    let script = root.join("matrix.sh");
    std::fs::write(&script, matrix_script(&root, &base_config, &script_cases)).unwrap();
    let run = sandbox.run_for(&["bash", &script.to_string_lossy()], &[], 1800);
    run.assert_success();

    let baseline = read_case(&baseline_dir);
    assert_eq!(baseline.rc, 0, "baseline: {:?}", baseline.lines);
    assert!(baseline.hwm_kb > 0, "no memory reading");
    let mut table = vec![format!(
        "{:<14} {:<14} {:>6} {:>8} {:>7}  line",
        "setting", "input", "frames", "peak MB", "line s"
    )];
    table.push(format!(
        "{:<14} {:<14} {:>6} {:>8.1} {:>7}",
        "baseline",
        "valid image",
        frames_of(&baseline),
        baseline.hwm_kb as f64 / 1024.0,
        "-"
    ));
    let mut failures = Vec::new();
    for c in &cases {
        let r = read_case(&c.dir);
        let (line_s, said, problem) = judge(c, &r, baseline.hwm_kb);
        table.push(format!(
            "{:<14} {:<14} {:>6} {:>8.1} {:>7}  {}",
            c.setting.name,
            c.input.name,
            frames_of(&r),
            r.hwm_kb as f64 / 1024.0,
            line_s.map_or("-".into(), |s| format!("{s:.3}")),
            said
        ));
        if let Some(problem) = problem {
            failures.push(format!(
                "{} x {}: {problem}\n  lines: {:?}",
                c.setting.name, c.input.name, r.lines
            ));
        }
    }
    eprintln!("{}", table.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn frames_of(r: &CaseRun) -> u64 {
    r.report
        .as_ref()
        .and_then(|j| j["frames_submitted"].as_u64())
        .unwrap_or(0)
}

/// Checks one case: (seconds from the session's first line to the refusal, the refusal line,
/// what is wrong if anything).
fn judge(c: &Case, r: &CaseRun, baseline_kb: u64) -> (Option<f64>, String, Option<String>) {
    let wanted = layer_outcome(c.setting, c.input);
    let shown = c.named.display().to_string();
    // The refusal lines: naming the path (or the variable) and why; the start-up line that
    // lists the settings is not one.
    let refusals: Vec<&String> = match &wanted {
        Outcome::Refused(Some(words)) if words.contains("is not UTF-8 text") => r
            .lines
            .iter()
            .filter(|l| l.contains(words.as_str()))
            .collect(),
        Outcome::Refused(words) => r
            .lines
            .iter()
            .filter(|l| !l.starts_with("contrastxr ") && !l.starts_with("config file:"))
            .filter(|l| l.contains(&shown) && words.as_ref().is_none_or(|w| l.contains(w.as_str())))
            .collect(),
        Outcome::Ok => Vec::new(),
    };
    let line = refusals.first().copied();
    let said = line.cloned().unwrap_or_default();
    let line_s = line.and_then(|l| {
        let key = l.get(..l.len().min(60)).unwrap_or(l);
        seconds_to_line(&r.log, key)
    });
    let problem = |text: String| Some(text);
    let report = r.report.as_ref();
    let problem = if r.rc != 0 || report.is_none_or(|j| j["ok"] != true) {
        problem(format!("the app failed: exit {}", r.rc))
    } else if frames_of(r) < FRAMES.parse().unwrap() {
        problem(format!("{} frames", frames_of(r)))
    } else if r.hwm_kb > baseline_kb + 64 * 1024 {
        problem(format!("peak {} kB, baseline {baseline_kb} kB", r.hwm_kb))
    } else if matches!(wanted, Outcome::Refused(_)) && refusals.len() != 1 {
        problem(format!(
            "{} lines naming {shown} ({wanted:?})",
            refusals.len()
        ))
    } else if line_s.is_some_and(|s| s > 1.0) {
        problem(format!(
            "the line came {:.3} s after the layer loaded, its session began or its first frame",
            line_s.unwrap()
        ))
    } else {
        let modified = report
            .and_then(|j| j["frames_modified"].as_array())
            .map_or(0, Vec::len);
        let pass = c.setting.passes_through && matches!(wanted, Outcome::Refused(_));
        match (pass, modified) {
            (true, m) if m > 0 => problem(format!(
                "{m} frames changed though the background was refused"
            )),
            (false, 0) => problem("no frame enhanced".into()),
            _ => None,
        }
    };
    (line_s, said, problem)
}

// ---- a stalled file system (a hung network or FUSE mount) ----

/// With every look-up of a user's file stalled 2 s (`CONTRASTXR_FAULT=stalled-file-system`),
/// starting and stopping the config watcher (xrCreateInstance, xrDestroyInstance: the app's
/// thread) each return within 300 ms: no stat, read or join there waits for the file system.
/// Run in a child process of this test binary, where the fault is armed.
#[test]
fn a_stalled_file_system_never_holds_the_apps_thread() {
    const NAME: &str = "a_stalled_file_system_never_holds_the_apps_thread";
    if std::env::var_os("CONTRASTXR_FAULT").is_none() {
        let out = Command::new(std::env::current_exe().unwrap())
            .args(["--exact", NAME, "--nocapture", "--test-threads=1"])
            .env("CONTRASTXR_FAULT", "stalled-file-system")
            .output()
            .expect("run the child");
        let text = String::from_utf8_lossy(&out.stderr).into_owned()
            + &String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{text}");
        assert!(text.contains("1 passed"), "{text}");
        return;
    }
    let home = scratch_dir("stalled-fs");
    let config = home.join(".config/contrastxr/config.toml");
    std::fs::create_dir_all(config.parent().unwrap()).unwrap();
    std::fs::write(&config, "lambda_e = 0.3\n").unwrap();
    let home_s = home.to_string_lossy().into_owned();
    let env = contrastxr::config::Env::from_pairs([("HOME", home_s.as_str())]);
    let t = Instant::now();
    let (live, resolved) = contrastxr::config::Live::start("app", env, Box::new(|_| {}));
    let started = t.elapsed();
    eprintln!("started in {started:?}: {:?}", resolved.problems);
    // The watcher's first look-up (after its 200 ms poll) is under way, stalled.
    std::thread::sleep(Duration::from_millis(400));
    let t = Instant::now();
    live.stop();
    let stopped = t.elapsed();
    eprintln!("stopped in {stopped:?}");
    let bound = Duration::from_millis(300);
    assert!(started < bound, "Live::start took {started:?}");
    assert!(stopped < bound, "Live::stop took {stopped:?}");
    // The stalled read is said as a problem, and the defaults are used.
    assert!(
        resolved.problems.iter().any(|p| p.contains("to read")),
        "{:?}",
        resolved.problems
    );
}

/// The log file's file system hanging (`stalled-file-system`: every look-up or open of the
/// file takes 2 s, as under a hung network or FUSE mount), from the first open on, or only after
/// it (`stalled-file-system@1`, a mount that stops answering later): no line holds the app's
/// thread, the first included, since the file's every operation is its writer's (the log's own
/// thread), and every line reaches stderr. Each run in a child process of this test binary,
/// where the fault is armed.
#[test]
fn a_stalled_log_folder_never_holds_the_apps_thread() {
    const NAME: &str = "a_stalled_log_folder_never_holds_the_apps_thread";
    if std::env::var_os("CONTRASTXR_FAULT").is_none() {
        for fault in ["stalled-file-system", "stalled-file-system@1"] {
            let state = scratch_dir("stalled-log");
            let out = Command::new(std::env::current_exe().unwrap())
                .args(["--exact", NAME, "--nocapture", "--test-threads=1"])
                .env("CONTRASTXR_FAULT", fault)
                .env("XDG_STATE_HOME", &state)
                .output()
                .expect("run the child");
            let text = String::from_utf8_lossy(&out.stderr).into_owned()
                + &String::from_utf8_lossy(&out.stdout);
            assert!(out.status.success(), "{fault}: {text}");
            assert!(text.contains("1 passed"), "{fault}: {text}");
            let lines = text.matches("contrastxr: a later line").count();
            assert_eq!(lines, 10, "{fault}: {text}");
        }
        return;
    }
    let t = Instant::now();
    contrastxr::layer::log::info("the first line");
    let first = t.elapsed();
    let t = Instant::now();
    for _ in 0..10 {
        contrastxr::layer::log::info("a later line");
    }
    let later = t.elapsed();
    eprintln!("first line in {first:?}, ten more in {later:?}");
    assert!(
        first < Duration::from_millis(100),
        "the first line took {first:?}"
    );
    assert!(
        later < Duration::from_millis(100),
        "ten later lines took {later:?}"
    );
}

// ---- files the command line writes ----

/// A small picture to save.
fn picture() -> contrastxr::image::RgbaImage {
    contrastxr::image::RgbaImage {
        width: 8,
        height: 6,
        pixels: (0..48)
            .map(|i| [i as u8 * 5, 90, 200 - i as u8, 255])
            .collect(),
        has_alpha: false,
    }
}

/// A symbolic link at the name a PNG is saved to (planted in a shared folder) is replaced,
/// never written through: the file it points to keeps its bytes.
#[test]
fn saving_a_png_never_writes_through_a_link() {
    let dir = std::env::temp_dir().join(format!("contrastxr-png-link-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, b"keep me").unwrap();
    let path = dir.join("frame-0000.png");
    std::os::unix::fs::symlink(&victim, &path).unwrap();
    picture().save_png(&path).unwrap();
    assert_eq!(std::fs::read(&victim).unwrap(), b"keep me");
    assert!(!std::fs::symlink_metadata(&path).unwrap().is_symlink());
    assert_eq!(
        contrastxr::image::RgbaImage::load(&path).unwrap(),
        picture()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---- a large `image:` background ----

/// A 4000x3000 picture (12 megapixels) with the texture of a photo: smooth fields and noise, so
/// that it compresses as one does (about 24 MiB as a PNG), as RGB bytes.
fn photo_12mp() -> (u32, u32, Vec<u8>) {
    let (w, h) = (4000u32, 3000u32);
    let mut data = Vec::with_capacity((w * h * 3) as usize);
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    for y in 0..h {
        for x in 0..w {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let noise = (seed & 15) as u32;
            data.push(((x * 200 / w) + noise) as u8);
            data.push(((y * 180 / h) + noise) as u8);
            data.push((((x + y) * 100 / (w + h)) + 40 + noise) as u8);
        }
    }
    (w, h, data)
}

fn photo_png_12mp() -> Vec<u8> {
    let (w, h, data) = photo_12mp();
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&data).unwrap();
    writer.finish().unwrap();
    bytes
}

fn photo_jpeg_12mp() -> Vec<u8> {
    let (w, h, data) = photo_12mp();
    let mut bytes = Vec::new();
    jpeg_encoder::Encoder::new(&mut bytes, 90)
        .encode(&data, w as u16, h as u16, jpeg_encoder::ColorType::Rgb)
        .unwrap();
    bytes
}

/// The app's peak resident memory (VmHWM) with a 12-megapixel `image:` background, PNG or
/// JPEG, is within 100 MB of its peak with a `color:` background, on Vulkan and on OpenGL: the
/// image is shrunk as it loads to the camera size the background is used at, and prepared
/// there.
#[test]
fn a_12_megapixel_image_background_costs_about_what_a_colour_does() {
    let Some(sandbox) = sandbox() else { return };
    let root = scratch_dir("large-image");
    let photo = root.join("photo.png");
    std::fs::write(&photo, photo_png_12mp()).unwrap();
    let jpeg = root.join("photo.jpg");
    std::fs::write(&jpeg, photo_jpeg_12mp()).unwrap();
    let config = root.join("base.toml");
    std::fs::write(&config, "").unwrap();
    let image = OsString::from(format!("image:{}", photo.display()));
    let image_jpeg = OsString::from(format!("image:{}", jpeg.display()));
    let colour = OsString::from("color:#e0d020");
    let mut cases = Vec::new();
    for api in ["vulkan", "opengl"] {
        let kinds = [
            ("image", &image),
            ("jpeg", &image_jpeg),
            ("colour", &colour),
        ];
        for (kind, background) in kinds {
            let dir = root.join(format!("{api}-{kind}"));
            cases.push((api, kind, dir, background.clone()));
        }
    }
    let mut script = String::from("#!/bin/bash\nrun_case() {\n  local dir=\"$1\"; shift\n  mkdir -p \"$dir/state\"\n  XDG_STATE_HOME=\"$dir/state\" \"$@\" >\"$dir/stdout\" 2>\"$dir/stderr\" </dev/null &\n  local pid=$! hwm=0 k v rest waited=0\n  while kill -0 $pid 2>/dev/null; do\n    while read -r k v rest; do [ \"$k\" = VmHWM: ] && hwm=$v; done <\"/proc/$pid/status\" 2>/dev/null\n    sleep 0.05; waited=$((waited + 1))\n    [ $waited -gt 2400 ] && kill -9 $pid\n  done\n  wait $pid; echo $? >\"$dir/rc\"; echo $hwm >\"$dir/hwm_kb\"\n}\n");
    // A run of each API before the measured ones fills the shader and program caches: with
    // them empty, the first run builds the OpenGL programs on the layer's thread in the app's
    // process (llvmpipe's compiler adds its own, passing peak), whatever the background.
    let warm: Vec<_> = ["vulkan", "opengl"]
        .into_iter()
        .map(|api| {
            (
                api,
                "warm",
                root.join(format!("{api}-warm")),
                colour.clone(),
            )
        })
        .collect();
    for (api, _, dir, background) in warm.iter().chain(&cases) {
        let graphics = match *api {
            "opengl" => "--graphics opengl --format R8G8B8A8_SRGB",
            _ => "",
        };
        script.push_str(&format!(
            "run_case {} env CONTRASTXR=1 CONTRASTXR_FORCE=1 CONTRASTXR_INDICATOR=0 \
             CONTRASTXR_PIPELINES=wait CONTRASTXR_CONFIG={} CONTRASTXR_BACKGROUND={} \
             {XR_CLIENT} --json --frames 30 --size 96x72 {graphics}\n",
            bash_word(dir.as_os_str().as_encoded_bytes()),
            bash_word(config.as_os_str().as_encoded_bytes()),
            bash_word(background.as_encoded_bytes()),
        ));
    }
    let path = root.join("run.sh");
    std::fs::write(&path, script).unwrap();
    sandbox
        .run_x11_for(&["bash", &path.to_string_lossy()], &[], 1200)
        .assert_success();
    let mut peaks = std::collections::HashMap::new();
    for (api, kind, dir, _) in &cases {
        let r = read_case(dir);
        assert_eq!(r.rc, 0, "{api} {kind}: {:?}", r.lines);
        assert!(r.hwm_kb > 0, "{api} {kind}: no memory reading");
        assert!(
            r.lines.iter().any(|l| l.contains("processing frames")),
            "{api} {kind}: no frame enhanced: {:?}",
            r.lines
        );
        eprintln!("{api} {kind}: peak {:.1} MB", r.hwm_kb as f64 / 1024.0);
        peaks.insert((*api, *kind), r.hwm_kb as f64 / 1024.0);
    }
    for api in ["vulkan", "opengl"] {
        for kind in ["image", "jpeg"] {
            let more = peaks[&(api, kind)] - peaks[&(api, "colour")];
            assert!(
                more < 100.0,
                "{api}: the {kind} background's peak is {more:.1} MB above the colour's"
            );
        }
    }
}
