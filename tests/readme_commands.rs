//! Every `contrastxr ...` command that README.md and docs/ show, checked against the built tool.
//! Each one's subcommand must exist and know every option the text gives it (its `--help` names
//! them). The concrete examples are also run, through `sh`, with HOME and XDG folders of their
//! own and a scratch working folder (with `samples/`): each must still exit with the status and
//! print the words [`RUN`] holds. A concrete example that neither [`RUN`] nor [`NOT_RUN`] knows
//! fails, so a new example in the text gets a check.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const REPO: &str = env!("CARGO_MANIFEST_DIR");
const TOOL: &str = env!("CARGO_BIN_EXE_contrastxr");

/// An example run: its exit status (None: depends on the machine, e.g. doctor's findings) and
/// words its output (stdout, then stderr) must hold.
struct Run {
    command: &'static str,
    status: Option<i32>,
    says: &'static str,
}

const fn run(command: &'static str, status: Option<i32>, says: &'static str) -> Run {
    Run {
        command,
        status,
        says,
    }
}

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
    run(
        "contrastxr config print --device \"Monado: Rokid Max\"",
        Some(0),
        "# device profiles: ",
    ),
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
    run("contrastxr uninstall --user", Some(0), "not installed"),
    run(
        "contrastxr evaluate --display samples/display-hand-interaction.png --background \
         samples/background-yellow-wall.png --sweep 0.2,0.4,0.6,0.8,1.0 --figure sweep.png",
        Some(0),
        "lambda_e foreground   enhanced",
    ),
];

/// Concrete examples not run here, and why.
const NOT_RUN: &[(&str, &str)] = &[
    (
        "contrastxr install --user",
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

/// The command a shown line runs, as `contrastxr ...` without `sudo`, the tool's path or a
/// trailing comment; None for other lines.
fn normalise(line: &str) -> Option<String> {
    let line = line.trim();
    let line = line.strip_prefix("sudo ").unwrap_or(line);
    let rest = [
        "\"$(command -v contrastxr)\" ",
        "target/release/contrastxr ",
        "contrastxr ",
    ]
    .iter()
    .find_map(|p| line.strip_prefix(p))?;
    let rest = rest.split("  #").next().unwrap_or(rest).trim();
    Some(format!("contrastxr {rest}"))
}

/// Every `contrastxr` command in `text`: the lines of indented code blocks (a trailing `\`
/// joins the next line) and inline code spans (which may wrap, so a paragraph is read whole).
fn commands(text: &str) -> Vec<String> {
    let spans = |paragraph: &str| -> Vec<String> {
        let code = paragraph.split('`').skip(1).step_by(2);
        code.filter_map(normalise).collect()
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
            found.extend(normalise(&joined));
        }
    }
    found.extend(spans(&paragraph));
    found
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

/// What is wrong with the subcommands and options `command` names, if anything.
fn syntax_problems(command: &str) -> Vec<String> {
    let mut problems = Vec::new();
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
            if !text.contains(option.as_str()) {
                problems.push(format!(
                    "`{command}`: `contrastxr {sub} --help` has no {option}"
                ));
            }
        }
    }
    problems
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

/// Runs `command` through `sh` with the built tool first on PATH, in folders of its own.
fn run_isolated(n: usize, command: &str) -> Output {
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

#[test]
fn every_shown_command_names_options_its_subcommand_knows() {
    let problems: Vec<String> = shown()
        .iter()
        .flat_map(|(file, c)| {
            syntax_problems(c)
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
        let o = run_isolated(n, r.command);
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
        ["contrastxr install --system", "contrastxr log --all"]
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

/// The README's short config is one `contrastxr config check` accepts.
#[test]
fn the_readmes_short_config_is_valid() {
    let readme = std::fs::read_to_string(Path::new(REPO).join("README.md")).unwrap();
    let after = readme
        .split_once("### A short config")
        .expect("the README has a short config")
        .1;
    let block: Vec<&str> = after
        .lines()
        .skip_while(|l| !l.starts_with("    "))
        .take_while(|l| l.starts_with("    ") || l.is_empty())
        .map(|l| l.strip_prefix("    ").unwrap_or(l))
        .collect();
    assert!(block.iter().any(|l| l.starts_with("[device.")), "{block:?}");
    let file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("readme-short-config.toml");
    std::fs::write(&file, block.join("\n")).unwrap();
    let o = Command::new(TOOL)
        .args(["config", "check"])
        .arg(&file)
        .output()
        .unwrap();
    let said =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{said}");
    assert!(said.ends_with(": ok\n"), "{said}");
}
