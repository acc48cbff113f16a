//! Helpers for tests that run OpenXR apps against the real Monado runtime in the sandbox
//! (`scripts/xr-sandbox`).
//!
//! - [`sandbox`] gives the sandbox, or `None` (with one line saying how to set it up) when it is
//!   not set up; with `CONTRASTXR_REQUIRE_SANDBOX=1` it builds it instead, and a sandbox that
//!   cannot be had fails the test with the reason.
//! - [`Sandbox::run`] runs a command inside with a fresh monado-service.
//! - [`Validation`] turns on the OpenXR core validation layer and the Vulkan validation layer's log
//!   file for a run and reads back what they reported, independently of the app.
//! - [`ApiDump`] records every OpenXR call of a run (LunarG api_dump) and answers questions on it.
#![allow(dead_code)] // each test crate uses a different part

pub mod capture_check;
pub mod conformance;
pub mod gl_client;
pub mod images;
pub mod pass_through;
pub mod semantics;
pub mod session_memory;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus};
use std::sync::OnceLock;

pub const XR_CLIENT: &str = env!("CARGO_BIN_EXE_contrastxr-xr-client");
const REQUIRE_VAR: &str = "CONTRASTXR_REQUIRE_SANDBOX";
/// The longest one sandbox run may take; exit status 124 means it was stopped. A guard against
/// a hung app or runtime, not a timing check: on a loaded machine with a cold cache, the layer's
/// OpenGL build alone (on a thread below the app's priority) can take over a minute.
pub const RUN_TIMEOUT_S: u64 = 300;

pub struct Sandbox {
    script: PathBuf,
}

/// What a command run in the sandbox did. `stdout` and `stderr` are the command's (and the
/// runtime client library's) output; the script's own messages are in `stderr` too.
pub struct SandboxRun {
    pub status: ExitStatus,
    pub stdout: String,
    pub stderr: String,
}

/// The sandbox, or `None` when it is not set up and not required (the test should return).
pub fn sandbox() -> Option<Sandbox> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/xr-sandbox");
    let required = std::env::var(REQUIRE_VAR).is_ok_and(|v| v == "1");
    let problem = match unavailable_reason(&script) {
        None => {
            build_layer_once();
            return Some(Sandbox { script });
        }
        Some(problem) => problem,
    };
    if !required {
        say_skipped_once(&problem);
        return None;
    }
    if let Err(reason) = setup_once(&script) {
        panic!("the XR sandbox is required ({REQUIRE_VAR}=1) but {problem}, and setting it up failed: {reason}");
    }
    build_layer_once();
    Some(Sandbox { script })
}

/// `cargo test` does not rebuild the cdylib (target/debug/libcontrastxr.so) that the sandbox
/// installs as the layer: build it once per test binary so no test runs a stale layer.
fn build_layer_once() {
    static BUILT: OnceLock<()> = OnceLock::new();
    BUILT.get_or_init(|| {
        let status = Command::new(env!("CARGO"))
            .args(["build", "--lib", "--quiet", "--manifest-path"])
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
            .status()
            .expect("run cargo to build the layer library");
        assert!(
            status.success(),
            "building the layer library (cargo build --lib) failed"
        );
    });
}

/// One line per test binary, written past the test harness's output capture so it is seen.
fn say_skipped_once(problem: &str) {
    static SAID: OnceLock<()> = OnceLock::new();
    SAID.get_or_init(|| {
        let _ = writeln!(
            std::io::stderr(),
            "XR runtime tests skipped: {problem}; run `scripts/xr-sandbox setup` as root \
             (or set {REQUIRE_VAR}=1) to run them"
        );
    });
}

fn unavailable_reason(script: &Path) -> Option<String> {
    if !is_root() {
        return Some("the XR sandbox needs root (chroot and mount namespaces)".into());
    }
    let ready = Command::new(script)
        .arg("status")
        .output()
        .is_ok_and(|o| o.status.success());
    (!ready).then(|| "the XR sandbox root is not set up".into())
}

/// Builds the root at most once per test binary, however many tests ask at once.
fn setup_once(script: &Path) -> Result<(), String> {
    static SETUP: OnceLock<Result<(), String>> = OnceLock::new();
    SETUP
        .get_or_init(|| {
            if !is_root() {
                return Err("tests are not running as root".into());
            }
            match Command::new(script).arg("setup").status() {
                Ok(s) if s.success() => Ok(()),
                Ok(s) => Err(format!(
                    "`scripts/xr-sandbox setup` exited with {s} (its message is above)"
                )),
                Err(e) => Err(format!("cannot run {}: {e}", script.display())),
            }
        })
        .clone()
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

impl Sandbox {
    /// The sandbox's root folder as `scripts/xr-sandbox status` names it ("ready: <root>"): the
    /// script is the one place that spells the cache layout.
    pub fn root(&self) -> PathBuf {
        let o = Command::new(&self.script).arg("status").output().unwrap();
        let out = String::from_utf8_lossy(&o.stdout);
        match out.trim().strip_prefix("ready: ") {
            Some(root) if o.status.success() => PathBuf::from(root),
            _ => panic!("xr-sandbox status names no ready root: {out}"),
        }
    }

    /// Runs `cmd` inside the sandbox with a fresh monado-service and returns what it did.
    /// `env` is added to the environment of the script, which passes CONTRASTXR*, XR_*, VK_*,
    /// LP_*, RUST_*, MESA_* variables to the command. Stdin is empty.
    pub fn run(&self, cmd: &[&str], env: &[(&str, &str)]) -> SandboxRun {
        self.run_for(cmd, env, RUN_TIMEOUT_S)
    }
}

impl SandboxRun {
    pub fn success(&self) -> bool {
        self.status.success()
    }

    /// Everything, for a failed assertion's message.
    pub fn describe(&self) -> String {
        format!(
            "{}\n--- stdout ---\n{}\n--- stderr ---\n{}",
            self.status,
            tail(&self.stdout),
            tail(&self.stderr)
        )
    }

    /// The XR test client's `--json` report: the last stdout line that is one (layers and the
    /// validation layer may print after it).
    #[track_caller]
    pub fn client_report(&self) -> serde_json::Value {
        self.stdout
            .lines()
            .rev()
            .filter(|l| l.starts_with("{\"ok\""))
            .find_map(|l| serde_json::from_str(l).ok())
            .unwrap_or_else(|| panic!("no JSON report from the client: {}", self.describe()))
    }

    #[track_caller]
    pub fn assert_success(&self) -> &Self {
        assert!(self.success(), "the command failed: {}", self.describe());
        self
    }
}

fn tail(text: &str) -> &str {
    const KEEP: usize = 6000;
    let start = text.len().saturating_sub(KEEP);
    let start = (start..text.len())
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(text.len());
    &text[start..]
}

/// A file for one run's logs, under the target directory (visible inside the sandbox at the same
/// path). Any previous file of that name is removed.
pub fn scratch_file(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xr-runtime");
    std::fs::create_dir_all(&dir).expect("create the scratch directory");
    let path = dir.join(name);
    let _ = std::fs::remove_file(&path);
    path
}

/// The shader cache folder the sandbox runs share (inside the target directory, which the
/// sandbox mounts).
fn shared_cache() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xr-cache");
    std::fs::create_dir_all(&dir).expect("create the shared cache directory");
    dir
}

/// The OpenXR core validation layer and the Vulkan validation layer's log, for one run.
pub struct Validation {
    xr_log: String,
    vk_log: String,
    xr_layers: String,
}

impl Validation {
    /// `tag` names the log files; it must be unique among tests running at once.
    pub fn new(tag: &str) -> Validation {
        let path = |kind: &str| {
            scratch_file(&format!("{tag}.{kind}.log"))
                .to_string_lossy()
                .into_owned()
        };
        Validation {
            xr_log: path("xr-validation"),
            vk_log: path("vk-validation"),
            xr_layers: "XR_APILAYER_LUNARG_core_validation".into(),
        }
    }

    /// Also enables this OpenXR API layer (e.g. api_dump) in the same run.
    pub fn with_xr_layer(mut self, name: &str) -> Validation {
        self.xr_layers = format!("{}:{name}", self.xr_layers);
        self
    }

    /// The variables that turn the layers on. The Vulkan layer is not forced on: the app enables
    /// it (hello_xr always; the client with `--validation`); these make it log to a file.
    pub fn env(&self) -> Vec<(&str, &str)> {
        vec![
            ("XR_ENABLE_API_LAYERS", self.xr_layers.as_str()),
            ("XR_CORE_VALIDATION_EXPORT_TYPE", "text"),
            ("XR_CORE_VALIDATION_FILE_NAME", self.xr_log.as_str()),
            ("VK_KHRONOS_VALIDATION_LOG_FILENAME", self.vk_log.as_str()),
            (
                "VK_KHRONOS_VALIDATION_DEBUG_ACTION",
                "VK_DBG_LAYER_ACTION_LOG_MSG",
            ),
            ("VK_KHRONOS_VALIDATION_REPORT_FLAGS", "error,warn"),
        ]
    }

    /// Core validation messages of severity error. Panics if the layer did not run.
    pub fn xr_errors(&self) -> Vec<String> {
        let log = std::fs::read_to_string(&self.xr_log).unwrap_or_else(|e| {
            panic!(
                "the OpenXR core validation layer wrote no log ({}): {e}",
                self.xr_log
            )
        });
        assert!(
            log.contains("Core Validation Layer is initialized"),
            "core validation did not start:\n{log}"
        );
        log.lines()
            .filter(|l| l.contains("[VALID_ERROR"))
            .map(String::from)
            .collect()
    }

    /// Vulkan validation errors. Panics if the layer did not run (it creates the log on load).
    pub fn vk_errors(&self) -> Vec<String> {
        let log = std::fs::read_to_string(&self.vk_log).unwrap_or_else(|e| {
            panic!(
                "the Vulkan validation layer was not loaded, no log at {}: {e}",
                self.vk_log
            )
        });
        let warnings = log
            .lines()
            .filter(|l| l.starts_with("Validation Warning"))
            .count();
        if warnings > 0 {
            eprintln!("{warnings} Vulkan validation warnings, see {}", self.vk_log);
        }
        log.lines()
            .filter(|l| l.starts_with("Validation Error"))
            .map(String::from)
            .collect()
    }

    #[track_caller]
    pub fn assert_clean(&self) {
        let (xr, vk) = (self.xr_errors(), self.vk_errors());
        assert!(
            xr.is_empty(),
            "OpenXR core validation errors ({}):\n{}",
            self.xr_log,
            xr.join("\n")
        );
        assert!(
            vk.is_empty(),
            "Vulkan validation errors ({}):\n{}",
            self.vk_log,
            vk.join("\n")
        );
    }
}

/// The LunarG api_dump layer's text record of one run's OpenXR calls.
pub struct ApiDump {
    file: String,
}

/// One recorded call: its `name = value` lines, e.g. `("createInfo->format", "50")`.
pub struct Call {
    pub fields: Vec<(String, String)>,
}

impl ApiDump {
    pub const LAYER: &'static str = "XR_APILAYER_LUNARG_api_dump";

    pub fn new(tag: &str) -> ApiDump {
        ApiDump {
            file: scratch_file(&format!("{tag}.api-dump.txt"))
                .to_string_lossy()
                .into_owned(),
        }
    }

    /// Enable the layer itself with [`ApiDump::LAYER`] in `XR_ENABLE_API_LAYERS`.
    pub fn env(&self) -> Vec<(&str, &str)> {
        vec![
            ("XR_API_DUMP_EXPORT_TYPE", "text"),
            ("XR_API_DUMP_FILE_NAME", self.file.as_str()),
        ]
    }

    /// Every call of the named function, in order.
    pub fn calls(&self, function: &str) -> Vec<Call> {
        let text = std::fs::read_to_string(&self.file)
            .unwrap_or_else(|e| panic!("api_dump wrote nothing at {}: {e}", self.file));
        let header = format!("XrResult {function}");
        let mut calls = Vec::new();
        let mut current: Option<Call> = None;
        for line in text.lines() {
            if !line.starts_with(' ') {
                calls.extend(current.take());
                current = (line.trim_end() == header).then(|| Call { fields: Vec::new() });
            } else if let (Some(call), Some((lhs, value))) =
                (current.as_mut(), line.split_once(" = "))
            {
                let name = lhs.rsplit(' ').next().unwrap_or_default();
                call.fields
                    .push((name.to_string(), value.trim().to_string()));
            }
        }
        calls.extend(current);
        calls
    }
}

impl Call {
    /// The value of a field, e.g. `call.get("createInfo->arraySize")`.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// A field's value as an integer (api_dump writes some in hex).
    pub fn int(&self, name: &str) -> Option<i64> {
        let v = self.get(name)?;
        match v.strip_prefix("0x") {
            Some(hex) => i64::from_str_radix(hex, 16).ok(),
            None => v.parse().ok(),
        }
    }
}

/// The `contrastxr` CLI built with the tests.
pub const CLI: &str = env!("CARGO_BIN_EXE_contrastxr");

/// The lines the contrastxr layer logged in a run (its stderr lines start with `contrastxr: `).
pub fn layer_lines(run: &SandboxRun) -> Vec<String> {
    run.stderr
        .lines()
        .filter_map(|l| l.strip_prefix("contrastxr: "))
        .map(String::from)
        .collect()
}

/// The line the layer writes when the app's exit waited for its driver work.
pub const EXIT_WAITED: &str = "contrastxr: the app's exit waited";

/// Where the app's exit waited for driver work of the layer's, it did so before the exit
/// handler the client registered last (`--exit-marker`), and so before any destructor a driver
/// registered during the session: a compile still running must not outlive them.
pub fn assert_exit_waits_first(tag: &str, stderr: &str) {
    let waited = stderr.find(EXIT_WAITED);
    let marker = stderr.find("contrastxr-xr-client: exit handler ran");
    assert!(
        marker.is_some(),
        "{tag}: the client's exit handler did not run"
    );
    if let Some(waited) = waited {
        assert!(
            waited < marker.unwrap(),
            "{tag}: exit waited after the handlers: {stderr}"
        );
    }
}

/// Turns on the Vulkan validation layer's synchronisation validation (the app enables the
/// layer itself; this is its documented settings variable).
pub const SYNC_VALIDATION: (&str, &str) = ("VK_KHRONOS_VALIDATION_VALIDATE_SYNC", "true");

/// Whether `path` exists within `timeout` (polled every 50 ms): a file a running app writes.
pub fn wait_for(path: &Path, timeout: std::time::Duration) -> bool {
    let end = std::time::Instant::now() + timeout;
    while std::time::Instant::now() < end {
        if path.exists() {
            return true;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    false
}

/// A fresh scratch folder under the target directory (visible inside the sandbox).
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = scratch_file(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create a scratch folder");
    dir
}

impl Sandbox {
    /// [`Sandbox::run`] with its own time limit in seconds (long soaks).
    pub fn run_for(&self, cmd: &[&str], env: &[(&str, &str)], timeout_s: u64) -> SandboxRun {
        self.run_with(&[], cmd, env, timeout_s)
    }

    /// [`Sandbox::run`] where the command may change the root (`run --overlay`): its changes
    /// go to a layer that ends with the run.
    pub fn run_overlay(&self, cmd: &[&str], env: &[(&str, &str)]) -> SandboxRun {
        self.run_with(&["--overlay"], cmd, env, RUN_TIMEOUT_S)
    }

    /// [`Sandbox::run`] with an X server beside the service (`run --x11`), for OpenGL apps.
    pub fn run_x11(&self, cmd: &[&str], env: &[(&str, &str)]) -> SandboxRun {
        self.run_with(&["--x11"], cmd, env, RUN_TIMEOUT_S)
    }

    /// [`Sandbox::run_x11`] with its own time limit in seconds.
    pub fn run_x11_for(&self, cmd: &[&str], env: &[(&str, &str)], timeout_s: u64) -> SandboxRun {
        self.run_with(&["--x11"], cmd, env, timeout_s)
    }

    fn run_with(
        &self,
        options: &[&str],
        cmd: &[&str],
        env: &[(&str, &str)],
        timeout_s: u64,
    ) -> SandboxRun {
        // A hung app or runtime must fail the test, not hang it: `timeout` signals the script's
        // whole process group, and the script's PID namespace takes everything inside down.
        let output = Command::new("timeout")
            .args(["--kill-after=10", &timeout_s.to_string()])
            .arg(&self.script)
            .arg("run")
            .args(options)
            .arg("--")
            .args(cmd)
            // Frames counted and captured from the first on: the first frame waits for the
            // layer's pipelines (tests of the default, "background", set it themselves).
            .env("CONTRASTXR_PIPELINES", "wait")
            // One shader cache for the runs of all tests (Mesa's and the layer's): the driver
            // compiles each shader once, not once per run (tests/startup.rs sets its own).
            .env("XDG_CACHE_HOME", shared_cache())
            .envs(env.iter().copied())
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap_or_else(|e| panic!("cannot run {}: {e}", self.script.display()));
        SandboxRun {
            status: output.status,
            stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        }
    }
}

/// Builds the V4L2 stand-in (tests/fake-v4l2, an LD_PRELOAD library; docs/camera.md) into
/// `dir` with the C compiler.
pub fn fake_v4l2(dir: &Path) -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fake-v4l2/fake_v4l2.c");
    let lib = dir.join("libfake_v4l2.so");
    let status = Command::new(std::env::var("CC").unwrap_or_else(|_| "cc".into()))
        .args(["-shared", "-fPIC", "-O2", "-Wall", "-o"])
        .arg(&lib)
        .arg(&source)
        .args(["-ldl", "-lpthread"])
        .status()
        .expect("a C compiler (cc) is needed to build the V4L2 stand-in");
    assert!(status.success(), "building {} failed", source.display());
    lib
}

/// The head of a shell pipeline feeding an app that runs until its stdin closes (hello_xr):
/// open for at least `min_s` seconds, then until `dir` holds `views` captured views
/// (`frame-N-view-V.json`), at most 180 s. A cold shader cache (a fresh machine's) or a loaded
/// machine then still gives the frames a test needs, where no fixed wait suits both.
pub fn stdin_until_captured(dir: &Path, views: usize, min_s: u32) -> String {
    format!(
        "(for i in $(seq 900); do [ $i -gt {} ] && [ $(ls '{}'/frame-*-view-*.json 2>/dev/null | wc -l) -ge {views} ] && break; sleep 0.2; done)",
        min_s * 5,
        dir.display()
    )
}
