//! Every `contrastxr ...` command that README.md and docs/ show, checked against the built tool.
//! Each one's subcommand must exist and know every option the text gives it, word for word (its
//! `--help` names them). The concrete examples are also run, through `sh`, with HOME and XDG
//! folders of their own and a scratch working folder (with `samples/`): each must still exit
//! with the status and print the words [`RUN`] holds. A concrete example that neither [`RUN`] nor
//! [`NOT_RUN`] knows fails, so a new example in the text gets a check. A command may start with
//! `NAME=value` words: a `CONTRASTXR_*` name must be one the project reads. `scripts/...` and
//! `cargo ...` commands are not run: the script, the test or example, and each option must
//! exist. The config snippets shown must pass `contrastxr config check`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const REPO: &str = env!("CARGO_MANIFEST_DIR");
const TOOL: &str = env!("CARGO_BIN_EXE_contrastxr");

/// An example run: its exit status (None: depends on the machine, e.g. doctor's findings),
/// words its output (stdout, then stderr) must hold, and variables it runs with.
struct Run {
    command: &'static str,
    status: Option<i32>,
    says: &'static str,
    env: &'static [(&'static str, &'static str)],
}

const fn run(command: &'static str, status: Option<i32>, says: &'static str) -> Run {
    Run {
        command,
        status,
        says,
        env: &[],
    }
}

/// The shipped profiles, as `install` puts them beside the library.
const PROFILES: &[(&str, &str)] = &[(
    "CONTRASTXR_DEVICES",
    concat!(env!("CARGO_MANIFEST_DIR"), "/devices.toml"),
)];

const RUN: &[Run] = &[
    run("contrastxr --version", Some(0), "contrastxr 0.1.0"),
    run("contrastxr doctor", None, "contrastxr doctor\n"),
    run(
        "contrastxr log",
        Some(1),
        "no app has run with the layer yet",
    ),
    run("contrastxr toggle", Some(0), "mode = \"off\""),
    run("contrastxr toggle heatmap", Some(0), "mode = \"off\""),
    run(
        "contrastxr config path",
        Some(0),
        "/config/contrastxr/config.toml\n",
    ),
    // A value from the headset's shipped profile, with its origin: the profile applied.
    Run {
        command: "contrastxr config print --device \"Monado: Rokid Max\"",
        status: Some(0),
        says: "devices.toml [device.\"Monado: Rokid Max\"]:",
        env: PROFILES,
    },
    run(
        "contrastxr config print --device \"Monado: Simulated HMD\"",
        Some(0),
        "on system \"Monado: Simulated HMD\"",
    ),
    run("contrastxr set lambda_e 0.6", Some(0), "lambda_e = 0.6"),
    run(
        "contrastxr set lambda_e -0.1",
        Some(1),
        "lambda_e must be >= 0",
    ),
    run(
        "contrastxr set fov_offset=-0.1,0.2",
        Some(0),
        "fov_offset = [-0.1, 0.2]",
    ),
    run(
        "contrastxr set fov_offset=0.15,0.2",
        Some(0),
        "fov_offset = [0.15, 0.2]",
    ),
    run(
        "contrastxr set fov_scale=0.6,0.6",
        Some(0),
        "fov_scale = [0.6, 0.6]",
    ),
    run(
        "contrastxr set mode background",
        Some(0),
        "mode = \"background\"",
    ),
    run("contrastxr set mode enhance", Some(0), "mode = \"enhance\""),
    run(
        "contrastxr set --app hello_xr mode split",
        Some(0),
        "mode = \"split\"",
    ),
    run(
        "contrastxr set background v4l2:/dev/video2",
        Some(0),
        "background = \"v4l2:/dev/video2\"",
    ),
    run(
        "contrastxr set background image:$HOME/wall.jpg",
        Some(0),
        "/wall.jpg",
    ),
    run("contrastxr camera list", None, ""),
    // A variable before the command: the path it names shows in the output.
    run(
        "XDG_DATA_HOME=~/.var/app/APPID/data contrastxr doctor",
        None,
        "/.var/app/APPID/data/openxr/1/api_layers/implicit.d",
    ),
    run(
        "XDG_CONFIG_HOME=~/.var/app/APPID/config contrastxr set lambda_e 0.6",
        Some(0),
        "/.var/app/APPID/config/contrastxr/config.toml",
    ),
    run(
        "XDG_STATE_HOME=~/.var/app/APPID/.local/state contrastxr log",
        Some(1),
        "/.var/app/APPID/.local/state/contrastxr/layer.log: no app has run with the layer yet",
    ),
    run("contrastxr uninstall --user", Some(0), "not installed"),
    run(
        "contrastxr evaluate --display samples/display-hand-interaction.png --background \
         samples/background-yellow-wall.png --sweep 0.2,0.4,0.6,0.8,1.0 --figure sweep.png",
        Some(0),
        "lambda_e foreground   enhanced",
    ),
    run(
        "contrastxr evaluate --display samples/display-hand-interaction.png --background \
         samples/background-yellow-wall.png --compare paper,perceptual --world-nits 500 --json",
        Some(0),
        "\"method\": \"perceptual\"",
    ),
];

/// Concrete examples not run here, and why.
const NOT_RUN: &[(&str, &str)] = &[
    (
        "contrastxr bench --method perceptual --ablate classify-rows",
        "minutes on a CPU driver; tests/gpu_engine.rs and tests/opengl_engine.rs run its classify",
    ),
    (
        "contrastxr bench --path all --ablate all --runs 30",
        "a GPU's measurement (scripts/gpu-check runs it); tests/gpu_engine.rs runs --ablate and --path all",
    ),
    (
        "contrastxr bench --path all --runs 30",
        "a GPU's measurement (scripts/gpu-check runs it); tests/gpu_engine.rs runs --path all",
    ),
    (
        "contrastxr bench --runs 30",
        "a GPU's measurement (scripts/gpu-check runs it); tests/gpu_engine.rs runs the bench",
    ),
    (
        "contrastxr enhance --engine gpu",
        "a start-up measurement without its files (scripts/gpu-check names them); tests/gpu_engine.rs runs it",
    ),
    (
        "contrastxr gl-programs --format 0x8C43 --width 1920",
        "a start-up measurement on a GPU (scripts/gpu-check runs it)",
    ),
    (
        "contrastxr install --user",
        "needs the layer library built beside the tool; tests/cli.rs installs one",
    ),
    (
        "XDG_DATA_HOME=~/.var/app/APPID/data contrastxr install --user",
        "needs the layer library built beside the tool; tests/cli.rs installs one",
    ),
    ("contrastxr install --system", "writes system folders"),
    ("contrastxr uninstall --system", "writes system folders"),
    (
        "contrastxr calibrate --device \"NAME\"",
        "interactive, with an app",
    ),
    ("contrastxr camera test", "needs a camera (tests/camera.rs)"),
    (
        "contrastxr camera test /dev/video0 --frames 60 -o /tmp/frames",
        "needs a camera (tests/camera.rs)",
    ),
    (
        "contrastxr camera test /dev/video2 -o /tmp/frames",
        "needs a camera (tests/camera.rs)",
    ),
    (
        "contrastxr bench",
        "minutes; tests/gpu_engine.rs runs the bench",
    ),
    (
        "contrastxr bench --json",
        "minutes; tests/gpu_engine.rs runs it",
    ),
    ("contrastxr bench --content full", "minutes"),
    ("contrastxr bench --path both", "minutes"),
    (
        "contrastxr bench --path all",
        "minutes; tests/gpu_engine.rs runs it",
    ),
    (
        "contrastxr bench --engine vulkan --path all",
        "minutes; tests/gpu_engine.rs runs the Vulkan bench",
    ),
    (
        "contrastxr bench --engine opengl",
        "minutes; tests/opengl_engine.rs runs it",
    ),
    (
        "contrastxr bench --sizes 1268x720 --content full --runs 60",
        "minutes",
    ),
    (
        "contrastxr bench --sizes 1268x720,2064x2208 --content full --runs 100",
        "minutes",
    ),
    (
        "contrastxr bench --sizes 1268x720,2064x2208 --runs 10 --path both",
        "minutes",
    ),
    (
        "contrastxr bench --ablate",
        "a mention; tests/gpu_engine.rs runs --ablate",
    ),
    (
        "contrastxr bench --shader-stats",
        "a mention; tests/gpu_engine.rs runs --shader-stats",
    ),
    (
        "contrastxr bench --compile-only",
        "a mention; tests/compiler_statistics.rs runs it through scripts/shader-stats",
    ),
    (
        "contrastxr bench --sizes 2064x2208 --runs 8 --path copy --method perceptual",
        "minutes",
    ),
    (
        "contrastxr bench --sizes 1268x720,2064x2208 --runs 10 --path copy",
        "minutes",
    ),
    (
        "contrastxr bench --sizes 2064x2208 --runs 10 --path all --ablate all",
        "minutes; tests/gpu_engine.rs runs --ablate",
    ),
    (
        "contrastxr bench --engine opengl --sizes 2064x2208 --runs 10 --ablate all",
        "minutes; tests/opengl_engine.rs runs --ablate",
    ),
];

/// The markdown files whose commands are checked.
fn documents() -> Vec<PathBuf> {
    let mut files = vec![Path::new(REPO).join("README.md")];
    let docs = std::fs::read_dir(Path::new(REPO).join("docs")).expect("docs/");
    let mut md: Vec<PathBuf> = docs
        .map(|e| e.expect("docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    md.sort();
    files.extend(md);
    files
}

/// The `NAME=value` words a command starts with, and the rest.
fn split_assignments(command: &str) -> (Vec<&str>, &str) {
    let mut rest = command.trim_start();
    let mut assignments = Vec::new();
    while let Some((word, after)) = rest.split_once(' ') {
        let Some((name, _)) = word.split_once('=') else {
            break;
        };
        let is_name = name.starts_with(|c: char| c.is_ascii_uppercase() || c == '_')
            && name
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
        if !is_name {
            break;
        }
        assignments.push(word);
        rest = after.trim_start();
    }
    (assignments, rest)
}

/// The command a shown line runs, without `sudo` or a trailing comment: `contrastxr ...` (for
/// the tool's path too), `scripts/NAME ...` or `cargo ...`, after any `NAME=value` words; None
/// for other lines.
fn normalise(line: &str) -> Option<String> {
    let line = line.trim();
    let line = line.strip_prefix("sudo ").unwrap_or(line);
    let (assignments, rest) = split_assignments(line);
    let rest = rest.split("  #").next().unwrap_or(rest).trim();
    let tool = [
        "\"$(command -v contrastxr)\" ",
        "target/release/contrastxr ",
        "contrastxr ",
    ]
    .iter()
    .find_map(|p| rest.strip_prefix(p));
    let command = match tool {
        Some(args) => format!("contrastxr {}", args.trim()),
        None if rest.starts_with("cargo ") => rest.to_string(),
        None if rest
            .strip_prefix("scripts/")
            .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_alphanumeric())) =>
        {
            rest.to_string()
        }
        None => return None,
    };
    Some(
        assignments
            .iter()
            .map(|a| format!("{a} "))
            .collect::<String>()
            + &command,
    )
}

/// The commands of one shown line or span: `a && b` shows two.
fn normalise_all(line: &str) -> Vec<String> {
    line.split(" && ").filter_map(normalise).collect()
}

/// Every command in `text`: the lines of indented code blocks (a trailing `\` joins the next
/// line) and inline code spans (which may wrap, so a paragraph is read whole).
fn commands(text: &str) -> Vec<String> {
    let spans = |paragraph: &str| -> Vec<String> {
        let code = paragraph.split('`').skip(1).step_by(2);
        code.flat_map(normalise_all).collect()
    };
    let mut found = Vec::new();
    let mut paragraph = String::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if !line.starts_with("    ") && !line.trim().is_empty() {
            paragraph = format!("{paragraph} {}", line.trim());
            continue;
        }
        found.extend(spans(&paragraph));
        paragraph.clear();
        if line.starts_with("    ") {
            let mut joined = line.trim().to_string();
            while joined.ends_with('\\') {
                joined.pop();
                match lines.next() {
                    Some(next) => joined = format!("{} {}", joined.trim_end(), next.trim()),
                    None => break,
                }
            }
            found.extend(normalise_all(&joined));
        }
    }
    found.extend(spans(&paragraph));
    found
}

/// What a shown command runs.
#[derive(Debug, PartialEq)]
enum Kind {
    Tool,
    Script,
    Cargo,
}

fn kind(command: &str) -> Kind {
    match split_assignments(command).1 {
        c if c.starts_with("scripts/") => Kind::Script,
        c if c.starts_with("cargo ") => Kind::Cargo,
        _ => Kind::Tool,
    }
}

/// A synopsis or a mention rather than a runnable example: placeholders, alternatives, `...`.
fn is_synopsis(command: &str) -> bool {
    let placeholder = |w: &str| {
        let w = w.trim_matches(|c: char| "[]\"".contains(c));
        !w.is_empty() && w.chars().all(|c| c.is_ascii_uppercase() || c == '_')
            || w.starts_with('<')
            || w.contains("...")
            || w.ends_with(".png") && w.chars().next().is_some_and(|c| c.is_ascii_uppercase())
    };
    command.contains('[')
        || command.contains('|')
        || command.split_whitespace().count() < 3 && !command.contains("--")
        || command.split_whitespace().any(placeholder)
}

/// `--name` or `-x`, not a negative number.
fn is_option(word: &str) -> bool {
    let mut chars = word.chars();
    chars.next() == Some('-')
        && chars
            .next()
            .is_some_and(|c| c == '-' || c.is_ascii_alphabetic())
}

/// The `(subcommand, options)` parts of a synopsis: `a X | b Y` names two subcommands; a part
/// that starts with an option continues the one before (`[--app NAME | --device SYSTEM]`).
fn parts(command: &str) -> Vec<(String, Vec<String>)> {
    let mut parts: Vec<(String, Vec<String>)> = Vec::new();
    let body = command.strip_prefix("contrastxr").unwrap_or(command);
    for piece in body.split(" | ") {
        let words: Vec<&str> = piece.split_whitespace().collect();
        let options = words
            .iter()
            .flat_map(|w| w.split('|'))
            .map(|w| w.trim_matches(|c: char| "[]".contains(c)))
            .filter(|w| is_option(w))
            .map(|w| w.split('=').next().unwrap_or(w).to_string());
        let first = words.first().copied().unwrap_or("");
        match parts.last_mut() {
            Some(last) if first.starts_with('-') || first.starts_with('[') => {
                last.1.extend(options)
            }
            _ => parts.push((first.to_string(), options.collect())),
        }
    }
    parts
}

fn help(subcommand: &str) -> Output {
    let mut cmd = Command::new(TOOL);
    if !subcommand.starts_with('-') && !subcommand.is_empty() {
        cmd.arg(subcommand);
    }
    cmd.arg("--help").output().expect("run contrastxr --help")
}

/// Whether `text` names `option` as a word of its own: `--app` is not in `--app-images`.
fn mentions(text: &str, option: &str) -> bool {
    let part_of_name = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_';
    text.match_indices(option).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let after = text[at + option.len()..].chars().next();
        !before.is_some_and(part_of_name) && !after.is_some_and(part_of_name)
    })
}

/// What is wrong with the subcommands and options `command` names, if anything.
fn syntax_problems(command: &str) -> Vec<String> {
    let mut problems = Vec::new();
    let command = split_assignments(command).1;
    for (sub, options) in parts(command) {
        if sub.starts_with('<') || sub == "..." {
            continue;
        }
        let o = help(&sub);
        let text =
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
        if !o.status.success() {
            problems.push(format!(
                "`{command}`: `contrastxr {sub} --help` failed: {text}"
            ));
            continue;
        }
        for option in options.iter().filter(|o| o.as_str() != "--help") {
            if !mentions(&text, option) {
                problems.push(format!(
                    "`{command}`: `contrastxr {sub} --help` has no {option}"
                ));
            }
        }
    }
    problems
}

/// The words of a script's or cargo's command up to a bare `--` (what follows is another
/// program's), without a synopsis' brackets and alternatives.
fn own_words(command: &str) -> Vec<String> {
    command
        .split_whitespace()
        .take_while(|w| *w != "--")
        .flat_map(|w| w.split('|'))
        .map(|w| w.trim_matches(|c: char| "[]".contains(c)).to_string())
        .filter(|w| !w.is_empty())
        .collect()
}

/// What is wrong with a `scripts/NAME ...` command: a script, subcommand (a case label of the
/// script) or option the script does not have.
fn script_problems(command: &str) -> Vec<String> {
    let words = own_words(split_assignments(command).1);
    let script = &words[0];
    let Ok(text) = std::fs::read_to_string(Path::new(REPO).join(script)) else {
        return vec![format!("`{command}`: there is no {script}")];
    };
    let mut problems = Vec::new();
    let subcommand = words
        .get(1)
        .filter(|w| !w.starts_with('-') && w.chars().all(|c| c.is_ascii_lowercase() || c == '-'));
    if let Some(sub) = subcommand {
        if !text.contains(&format!("{sub})")) {
            problems.push(format!("`{command}`: {script} has no subcommand {sub}"));
        }
    }
    for option in words.iter().skip(1).filter(|w| is_option(w)) {
        let option = option.split('=').next().unwrap_or(option);
        if !mentions(&text, option) {
            problems.push(format!("`{command}`: {script} has no {option}"));
        }
    }
    problems
}

/// Cargo's own subcommands, whose `--help` lists their options; fmt, clippy and deb are
/// plugins, which a machine may lack.
const CARGO_OWN: &[&str] = &[
    "build", "test", "run", "clean", "check", "doc", "bench", "metadata",
];
const CARGO_PLUGINS: &[&str] = &["fmt", "clippy", "deb"];

/// What is wrong with a `cargo ...` command: a subcommand or option cargo does not have, a
/// test, example or binary the project does not have, a test filter that names no test.
fn cargo_problems(command: &str) -> Vec<String> {
    let words = own_words(split_assignments(command).1);
    let sub = words.get(1).map_or("", String::as_str);
    let mut problems = Vec::new();
    let value_of = |flag: &str| {
        let at = words.iter().position(|w| w == flag)?;
        words.get(at + 1).map(String::as_str)
    };
    let test = value_of("--test");
    let exists = |path: &str| Path::new(REPO).join(path).is_file();
    if let Some(t) = test.filter(|t| !exists(&format!("tests/{t}.rs"))) {
        problems.push(format!("`{command}`: there is no tests/{t}.rs"));
    }
    if let Some(e) = value_of("--example").filter(|e| !exists(&format!("examples/{e}.rs"))) {
        problems.push(format!("`{command}`: there is no examples/{e}.rs"));
    }
    let manifest = std::fs::read_to_string(Path::new(REPO).join("Cargo.toml")).unwrap();
    if let Some(b) = value_of("--bin").filter(|b| !manifest.contains(&format!("name = \"{b}\""))) {
        problems.push(format!("`{command}`: Cargo.toml has no binary {b}"));
    }
    // A test filter after `--test NAME`: that file has a test whose name holds it.
    const TAKES_VALUE: &[&str] = &[
        "--test",
        "--example",
        "--bin",
        "--features",
        "-p",
        "--package",
    ];
    let filters = words
        .iter()
        .enumerate()
        .skip(2)
        .filter(|(i, w)| !is_option(w) && !TAKES_VALUE.contains(&words[i - 1].as_str()));
    for (_, filter) in filters {
        let text = test.and_then(|t| {
            std::fs::read_to_string(Path::new(REPO).join(format!("tests/{t}.rs"))).ok()
        });
        if text.is_some_and(|t| {
            !t.contains(&format!("fn {filter}")) && !t.contains(&format!("_{filter}"))
        }) {
            problems.push(format!(
                "`{command}`: no test of {} is named after {filter}",
                test.unwrap_or("")
            ));
        }
    }
    if CARGO_PLUGINS.contains(&sub) {
        return problems;
    }
    if !CARGO_OWN.contains(&sub) {
        problems.push(format!("`{command}`: cargo has no subcommand {sub:?} here"));
        return problems;
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let Ok(o) = Command::new(cargo).args([sub, "--help"]).output() else {
        return problems;
    };
    let help = String::from_utf8_lossy(&o.stdout).into_owned();
    for option in words.iter().skip(2).filter(|w| is_option(w)) {
        let option = option.split('=').next().unwrap_or(option);
        if !mentions(&help, option) {
            problems.push(format!("`{command}`: `cargo {sub} --help` has no {option}"));
        }
    }
    problems
}

/// Every file's text under src/, tests/ and scripts/: what the project reads.
fn project_text() -> String {
    fn add(dir: &Path, text: &mut String) {
        for entry in std::fs::read_dir(dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                add(&path, text);
            } else if let Ok(t) = std::fs::read_to_string(&path) {
                text.push_str(&t);
                text.push('\n');
            }
        }
    }
    let mut text = String::new();
    for dir in ["src", "tests", "scripts"] {
        add(&Path::new(REPO).join(dir), &mut text);
    }
    text
}

/// The `CONTRASTXR...` names a command sets that nothing of the project reads.
fn assignment_problems(command: &str, project: &str) -> Vec<String> {
    split_assignments(command)
        .0
        .iter()
        .filter_map(|a| a.split_once('=').map(|(name, _)| name))
        .filter(|name| name.starts_with("CONTRASTXR") && !mentions(project, name))
        .map(|name| format!("`{command}`: nothing in src/, tests/ or scripts/ reads {name}"))
        .collect()
}

/// A folder for one run: HOME with its XDG folders, and a working folder with `samples/`.
fn fresh(n: usize) -> (PathBuf, PathBuf) {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("readme-commands")
        .join(n.to_string());
    let _ = std::fs::remove_dir_all(&root);
    let work = root.join("work");
    std::fs::create_dir_all(&work).unwrap();
    std::fs::create_dir_all(root.join("dev")).unwrap();
    std::os::unix::fs::symlink(Path::new(REPO).join("samples"), work.join("samples")).unwrap();
    (root, work)
}

/// Runs `command` through `sh` with the built tool first on PATH, in folders of its own, with
/// `env`.
fn run_isolated(n: usize, command: &str, env: &[(&str, &str)]) -> Output {
    let (root, work) = fresh(n);
    let tool_dir = Path::new(TOOL).parent().unwrap();
    let mut cmd = Command::new("sh");
    cmd.args(["-c", command]).current_dir(&work);
    for (name, _) in std::env::vars_os() {
        let name = name.to_string_lossy().into_owned();
        if ["CONTRASTXR", "XR_", "XDG_", "PRESSURE_VESSEL"]
            .iter()
            .any(|p| name.starts_with(p))
        {
            cmd.env_remove(&name);
        }
    }
    cmd.env("PATH", format!("{}:/usr/bin:/bin", tool_dir.display()))
        .env("HOME", &root)
        .env("XDG_CONFIG_HOME", root.join("config"))
        .env("XDG_DATA_HOME", root.join("data"))
        .env("XDG_STATE_HOME", root.join("state"))
        .env(
            "XDG_CACHE_HOME",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-cache"),
        )
        .env("CONTRASTXR_V4L2_DIR", root.join("dev"))
        .envs(env.iter().copied())
        .output()
        .expect("run sh")
}

/// Every command shown, with the file that shows it.
fn shown() -> Vec<(String, String)> {
    let mut all = Vec::new();
    for file in documents() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(REPO).unwrap().display().to_string();
        all.extend(commands(&text).into_iter().map(|c| (name.clone(), c)));
    }
    all.sort();
    all.dedup();
    all
}

/// What is wrong with a shown command, of any kind.
fn problems(command: &str, project: &str) -> Vec<String> {
    let mut found = assignment_problems(command, project);
    found.extend(match kind(command) {
        Kind::Tool => syntax_problems(command),
        Kind::Script => script_problems(command),
        Kind::Cargo => cargo_problems(command),
    });
    found
}

#[test]
fn every_shown_command_names_options_its_subcommand_knows() {
    let project = project_text();
    let shown = shown();
    for wanted in [Kind::Tool, Kind::Script, Kind::Cargo] {
        assert!(
            shown.iter().any(|(_, c)| kind(c) == wanted),
            "no {wanted:?} command found"
        );
    }
    assert!(
        shown.iter().any(|(_, c)| c.starts_with("XDG_DATA_HOME=")),
        "the commands that start with a variable are read"
    );
    let problems: Vec<String> = shown
        .iter()
        .flat_map(|(file, c)| {
            problems(c, &project)
                .into_iter()
                .map(move |p| format!("{file}: {p}"))
        })
        .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_concrete_example_is_run_or_excused() {
    let unknown: Vec<String> = shown()
        .into_iter()
        .filter(|(_, c)| kind(c) == Kind::Tool)
        .filter(|(_, c)| !is_synopsis(c))
        .filter(|(_, c)| !RUN.iter().any(|r| r.command == c))
        .filter(|(_, c)| !NOT_RUN.iter().any(|(n, _)| n == c))
        .map(|(file, c)| format!("{file}: `{c}`"))
        .collect();
    assert!(
        unknown.is_empty(),
        "examples with no check (add each to RUN or NOT_RUN):\n{}",
        unknown.join("\n")
    );
}

#[test]
fn the_examples_still_do_what_the_text_says() {
    let mut wrong = Vec::new();
    for (n, r) in RUN.iter().enumerate() {
        let o = run_isolated(n, r.command, r.env);
        let said =
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
        let status_ok = r.status.is_none_or(|s| o.status.code() == Some(s));
        if !status_ok || !said.contains(r.says) {
            wrong.push(format!(
                "`{}`: exit {:?} (wanted {:?}), wanted {:?} in:\n{said}",
                r.command,
                o.status.code(),
                r.status,
                r.says
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// Each example the table runs is still shown somewhere: a table entry outliving its text
/// would check nothing a reader sees.
#[test]
fn every_run_example_is_still_shown() {
    let shown = shown();
    let gone: Vec<&str> = RUN
        .iter()
        .map(|r| r.command)
        .chain(NOT_RUN.iter().map(|(c, _)| *c))
        .filter(|c| !shown.iter().any(|(_, s)| s == c))
        .collect();
    assert!(gone.is_empty(), "in the table but shown nowhere: {gone:?}");
}

/// The checks can fail: a wrong option, a missing subcommand and an unknown example are found.
#[test]
fn the_checks_find_what_is_wrong() {
    assert_eq!(
        syntax_problems("contrastxr bench [--no-such-option]").len(),
        1
    );
    assert_eq!(syntax_problems("contrastxr no-such-command").len(), 1);
    assert!(
        syntax_problems("contrastxr set [--app NAME] KEY VALUE | toggle [--app NAME] [MODE]")
            .is_empty()
    );
    assert!(!is_synopsis("contrastxr set lambda_e 0.7"));
    assert!(syntax_problems("contrastxr set lambda_e -0.1").is_empty());
    assert!(is_synopsis("contrastxr camera test DEVICE [--frames N]"));
    let text = "x\n\n    sudo target/release/contrastxr install --system   # all users\n\
                see `contrastxr log --all` and `cargo test`\n";
    assert_eq!(
        commands(text),
        [
            "contrastxr install --system",
            "contrastxr log --all",
            "cargo test"
        ]
    );
    // Options match word for word: evaluate's --app-images is no --app.
    assert!(syntax_problems("contrastxr evaluate --app-images").is_empty());
    assert_eq!(syntax_problems("contrastxr evaluate --app").len(), 1);
    // A command after variables is read, and checked, with them (a name made here, so that
    // this file does not hold it).
    let unread = ["CONTRASTXR", "NOT", "READ"].join("_");
    let text = format!(
        "    XDG_STATE_HOME=/x {unread}=1 contrastxr log --path\n\
         `cargo build --release && target/release/contrastxr bench`\n"
    );
    let found = commands(&text);
    assert_eq!(
        found,
        [
            format!("XDG_STATE_HOME=/x {unread}=1 contrastxr log --path"),
            "cargo build --release".into(),
            "contrastxr bench".into()
        ]
    );
    let project = project_text();
    assert_eq!(problems(&found[0], &project).len(), 1, "{found:?}");
    assert!(problems("CONTRASTXR_LOG=debug contrastxr log", &project).is_empty());
    // Scripts and cargo: the script, its subcommand and options, the test and its filter.
    assert!(problems("scripts/xr-sandbox run --x11 -- sh -c 'x --y'", &project).is_empty());
    assert_eq!(problems("scripts/no-such-script", &project).len(), 1);
    assert_eq!(problems("scripts/xr-sandbox walk", &project).len(), 1);
    assert_eq!(
        problems("scripts/soak --layer on --lay on", &project).len(),
        1
    );
    assert!(problems("cargo test --test hardening soak -- --nocapture", &project).is_empty());
    assert_eq!(
        problems("cargo test --test no_such_test", &project).len(),
        1
    );
    assert_eq!(
        problems("cargo test --test hardening no_such_filter", &project).len(),
        1
    );
    assert_eq!(problems("cargo build --relase", &project).len(), 1);
    assert_eq!(
        problems("cargo run --example no_such_example", &project).len(),
        1
    );
}

/// Variables for tests and development, documented where they are used rather than in the
/// README's table: fault points (docs/control.md), the V4L2 and sysfs stand-ins of the camera
/// tests, the GPU tests' device and validation switches, and a unit test's made-up name.
const NOT_FOR_USERS: &[&str] = &[
    "CONTRASTXR_FAULT",
    "CONTRASTXR_SYSFS_ROOT",
    "CONTRASTXR_V4L2_DIR",
    "CONTRASTXR_VK_DEVICE",
    "CONTRASTXR_VK_VALIDATION",
    "CONTRASTXR_X",
];

/// The `"CONTRASTXR_..."` string literals of the `.rs` files under `dir`.
fn variables_read(dir: &Path, found: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            variables_read(&path, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).unwrap();
            for piece in text.split("\"CONTRASTXR_").skip(1) {
                let name: String = piece
                    .chars()
                    .take_while(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || *c == '_')
                    .collect();
                if piece[name.len()..].starts_with('"') {
                    found.push(format!("CONTRASTXR_{name}"));
                }
            }
        }
    }
}

/// The README's table names every variable the code reads (settings_tables.rs checks the
/// config keys'; this also catches the others, such as `CONTRASTXR_DEVICES`).
#[test]
fn the_readme_names_every_variable_the_code_reads() {
    let mut read = Vec::new();
    variables_read(&Path::new(REPO).join("src"), &mut read);
    read.sort();
    read.dedup();
    assert!(read.iter().any(|v| v == "CONTRASTXR_DEVICES"), "{read:?}");
    let readme = std::fs::read_to_string(Path::new(REPO).join("README.md")).unwrap();
    let missing: Vec<&String> = read
        .iter()
        .filter(|v| !NOT_FOR_USERS.contains(&v.as_str()))
        .filter(|v| !readme.contains(&format!("| `{v}`")) && !readme.contains(&format!(", `{v}`")))
        .collect();
    assert!(missing.is_empty(), "README.md's table lacks {missing:?}");
}

/// The indented code blocks of `text`: (the line each starts on, its lines less the block's
/// indentation). A block starts after a blank line; a list item's block is indented further.
fn code_blocks(text: &str) -> Vec<(usize, Vec<String>)> {
    let lines: Vec<&str> = text.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let mut blocks = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let starts = indent(lines[i]) >= 4
            && !lines[i].trim().is_empty()
            && (i == 0 || lines[i - 1].trim().is_empty());
        if !starts {
            i += 1;
            continue;
        }
        let depth = indent(lines[i]);
        let mut block = Vec::new();
        let first = i;
        while i < lines.len() && (lines[i].trim().is_empty() || indent(lines[i]) >= depth) {
            block.push(lines[i].get(depth..).unwrap_or("").to_string());
            i += 1;
        }
        while block.last().is_some_and(|l| l.trim().is_empty()) {
            block.pop();
        }
        blocks.push((first + 1, block));
    }
    blocks
}

/// The config keys, as `contrastxr config print` lists them.
fn config_keys() -> Vec<String> {
    let o = Command::new(TOOL)
        .args(["config", "print"])
        .env("CONTRASTXR_CONFIG", "/nonexistent/contrastxr.toml")
        .output()
        .unwrap();
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| Some(l.split_once(" = ")?.0.to_string()))
        .collect()
}

/// Whether a block is a config snippet: each line a comment, a `[device."..."]` or
/// `[app."..."]` table, or a config key's `key = value`.
fn is_config(block: &[String], keys: &[String]) -> bool {
    let body: Vec<&str> = block
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect();
    !body.is_empty()
        && body.iter().all(|l| {
            l.starts_with("[device.\"")
                || l.starts_with("[app.\"")
                || l.split_once(" = ")
                    .is_some_and(|(k, _)| keys.iter().any(|key| key == k))
        })
}

/// Every config snippet of README.md and docs/ is one `contrastxr config check` accepts.
#[test]
fn every_config_snippet_is_valid() {
    let keys = config_keys();
    assert!(keys.iter().any(|k| k == "lambda_e"), "{keys:?}");
    let mut checked = Vec::new();
    let mut wrong = Vec::new();
    for file in documents() {
        let name = file.strip_prefix(REPO).unwrap().display().to_string();
        let text = std::fs::read_to_string(&file).unwrap();
        for (line, block) in code_blocks(&text) {
            if !is_config(&block, &keys) {
                continue;
            }
            let path = Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join(format!("snippet-{}-{line}.toml", name.replace('/', "-")));
            std::fs::write(&path, block.join("\n") + "\n").unwrap();
            let o = Command::new(TOOL)
                .args(["config", "check"])
                .arg(&path)
                .output()
                .unwrap();
            let said = String::from_utf8_lossy(&o.stdout).into_owned()
                + &String::from_utf8_lossy(&o.stderr);
            if !o.status.success() || !said.ends_with(": ok\n") {
                wrong.push(format!("{name}:{line}: {said}"));
            }
            checked.push(format!("{name}:{}", block.join("\n")));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    // The snippets known to be there were found: the README's short config (with a headset's
    // table), the camera profile of calibration.md and the USB ids of camera.md.
    for (file, holds) in [
        ("README.md", "[device.\"Monado: Rokid Max\"]"),
        ("docs/calibration.md", "camera_position = "),
        ("docs/camera.md", "camera_usb_ids = "),
    ] {
        assert!(
            checked
                .iter()
                .any(|c| c.starts_with(&format!("{file}:")) && c.contains(holds)),
            "no config snippet of {file} holding {holds}: {checked:#?}"
        );
    }
}

/// docs/control.md's fault-point table names every fault point and pause point of the code.
#[test]
fn control_md_lists_every_fault_point() {
    let text = std::fs::read_to_string(Path::new(REPO).join("docs/control.md")).unwrap();
    let missing: Vec<&str> = contrastxr::fault::POINTS
        .iter()
        .map(|(name, _)| *name)
        .filter(|name| !text.contains(&format!("| `{name}` |")))
        .chain(
            contrastxr::fault::PAUSES
                .iter()
                .map(|(name, _)| *name)
                .filter(|name| !text.contains(&format!("`{name}`"))),
        )
        .collect();
    assert!(missing.is_empty(), "docs/control.md lacks {missing:?}");
}

/// The options docs/xr-sandbox.md lists for the XR test client are ones its `--help` names.
#[test]
fn the_clients_options_in_xr_sandbox_md_exist() {
    let text = std::fs::read_to_string(Path::new(REPO).join("docs/xr-sandbox.md")).unwrap();
    let section = text
        .split_once("## The XR test client")
        .expect("xr-sandbox.md describes the client")
        .1;
    let section = section.split("\n## ").next().unwrap_or(section);
    let listed: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix("    ")?.split_whitespace().next())
        .filter(|w| w.starts_with("--"))
        .collect();
    assert!(listed.len() >= 10, "{listed:?}");
    let o = Command::new(env!("CARGO_BIN_EXE_contrastxr-xr-client"))
        .arg("--help")
        .output()
        .unwrap();
    let help =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    let missing: Vec<&&str> = listed.iter().filter(|o| !mentions(&help, o)).collect();
    assert!(missing.is_empty(), "the client's --help lacks {missing:?}");
}

/// docs/xr-sandbox.md names every variable prefix scripts/xr-sandbox passes into the root.
#[test]
fn xr_sandbox_md_names_every_variable_passed_in() {
    let script = std::fs::read_to_string(Path::new(REPO).join("scripts/xr-sandbox")).unwrap();
    let pattern = script
        .lines()
        .find_map(|l| l.strip_prefix("readonly PASS_ENV_RE='^("))
        .and_then(|l| l.strip_suffix(")'"))
        .expect("scripts/xr-sandbox has PASS_ENV_RE");
    let text = std::fs::read_to_string(Path::new(REPO).join("docs/xr-sandbox.md")).unwrap();
    let missing: Vec<&str> = pattern
        .split('|')
        .map(|p| p.trim_end_matches('='))
        .filter(|p| !text.contains(&format!("`{p}`")))
        .collect();
    assert!(missing.is_empty(), "docs/xr-sandbox.md lacks {missing:?}");
}

/// docs/development.md's source layout names every file and folder of `src/` (lib.rs aside)
/// and every folder of `src/gpu/` and `src/layer/`.
#[test]
fn development_md_names_every_source_folder() {
    let text = std::fs::read_to_string(Path::new(REPO).join("docs/development.md")).unwrap();
    let layout = text
        .split_once("## Source layout")
        .expect("development.md has a source layout")
        .1;
    let names = |dir: &str, folders_only: bool| -> Vec<String> {
        let mut found: Vec<String> = std::fs::read_dir(Path::new(REPO).join(dir))
            .unwrap()
            .flatten()
            .filter(|e| !folders_only || e.path().is_dir())
            .map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                match e.path().is_dir() {
                    true => format!("{name}/"),
                    false => name,
                }
            })
            .collect();
        found.sort();
        found
    };
    let mut missing: Vec<String> = names("src", false)
        .into_iter()
        .filter(|n| n != "lib.rs" && !layout.contains(&format!("src/{n}")))
        .collect();
    for dir in ["gpu", "layer"] {
        missing.extend(
            names(&format!("src/{dir}"), true)
                .into_iter()
                .filter(|n| !layout.contains(n.as_str()))
                .map(|n| format!("src/{dir}/{n}")),
        );
    }
    assert!(
        missing.is_empty(),
        "docs/development.md's layout lacks {missing:?}"
    );
}
