//! `contrastxr gl-programs`: builds the OpenGL programs an app's views need, in a context of its
//! own, into the layer's program binary cache and the driver's shader cache, ahead of time (the
//! layer builds what the caches lack on a thread of its own; it starts no process).

use std::time::Duration;

use super::args::{Args, Opt};
use super::error::CliError;
use super::options::{self, method_usage};
use contrastxr::algorithm::params::ViewMode;
use contrastxr::gpu::opengl::device::caps::same_driver;
use contrastxr::gpu::opengl::{gl_sources_id, GlFormat, GlOffline};

pub const OPTIONS: &[Opt] = &[
    Opt::value("--format", "GL_ENUM"),
    Opt::value("--width", "N"),
    Opt::value("--mode", "MODE"),
    Opt::value("--driver", "TEXT"),
    Opt::value("--sources", "HEX"),
];

/// How long the build may take before the tool gives up (the layer stops waiting then too).
const LIMIT: Duration = Duration::from_secs(60);

pub fn usage() -> String {
    format!(
        "usage: contrastxr gl-programs --format GL_ENUM --width N [--mode MODE] [--driver TEXT]\n\
         \x20                             [--sources HEX] [method options]\n\n\
         Builds the OpenGL programs views of one internal format (e.g. 0x8058, GL_RGBA8) and width\n\
         need, on an EGL context of its own, and runs them once, so that the layer's program\n\
         binary cache and the driver's shader cache hold them before an app needs them (the\n\
         layer builds what they lack on a thread of its own). --driver: an app's \"vendor |\n\
         renderer | version\"; the tool refuses to build for another driver (a profile such as\n\
         \"(Core Profile)\" is no part of it). --sources: the layer's program sources' id; the tool refuses\n\
         when its own differ (another build of contrastxr). --mode: enhance (default), split,\n\
         heatmap, background.\n\n{}",
        method_usage()
    )
}

fn number(text: &str, what: &str) -> Result<u32, CliError> {
    let parsed = match text.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => text.parse(),
    };
    parsed.map_err(|_| CliError::Failure(format!("{what} must be a number, got '{text}'")))
}

pub fn run(args: &mut Args) -> Result<(), CliError> {
    let format = number(&args.required(&["--format"])?, "--format")?;
    let width = number(&args.required(&["--width"])?, "--width")?;
    let mode = args.value(&["--mode"])?;
    let driver = args.value(&["--driver"])?;
    let sources = args.value(&["--sources"])?;
    let mut params = options::params(args)?;
    args.finish()?;
    if let Some(m) = mode {
        params.mode = ViewMode::parse(&m)
            .ok_or_else(|| CliError::Failure(format!("--mode: no mode '{m}'")))?;
    }
    GlFormat::of(format).map_err(|e| CliError::Failure(e.to_string()))?;
    if sources.is_some_and(|s| s != format!("{:016x}", gl_sources_id())) {
        return Err(CliError::Failure(
            "another build of contrastxr: its program sources differ from the layer's".into(),
        ));
    }
    lower_priority();
    close_inherited_files();
    contrastxr::gpu::core::cache_files::writes_may_wait();
    let mut gl = GlOffline::new().map_err(|e| CliError::Failure(e.to_string()))?;
    let own = gl.engine().caps().driver.clone();
    if driver.is_some_and(|d| !same_driver(&d, &own)) {
        return Err(CliError::Failure(format!("another driver here: {own}")));
    }
    // SAFETY: the offline context is current on this thread (GlOffline's contract).
    let built = unsafe { gl.engine().warm_up(format, width, &params, LIMIT) }
        .map_err(|e| CliError::Failure(e.to_string()))?;
    if !built {
        return Err(CliError::Failure(format!("not built within {LIMIT:?}")));
    }
    gl.engine().save_program_cache();
    super::error::print(&format!(
        "built the programs for {format:#06x} views {width} wide on {own}\n"
    ));
    Ok(())
}

/// Closes the files the app let its child inherit (descriptors without close-on-exec: its
/// sockets, pipes, device nodes), so that the build holds none of them open.
fn close_inherited_files() {
    let Ok(dir) = std::fs::read_dir("/proc/self/fd") else {
        return;
    };
    let fds: Vec<i32> = dir
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse().ok())
        .filter(|&fd| fd > 2)
        .collect();
    for fd in fds {
        // SAFETY: nothing of this process uses these descriptors: it opened none yet but the
        // listing's own, which was closed when the listing was dropped above (EBADF then).
        unsafe { libc::close(fd) };
    }
}

/// The app keeps the CPU first: this build runs beside its frames.
fn lower_priority() {
    // SAFETY: nice only changes this process's scheduling priority.
    unsafe { libc::nice(10) };
}
