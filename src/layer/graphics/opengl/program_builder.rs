//! The OpenGL programs built beside the app: `contrastxr gl-programs`, a process of its own with
//! a GL context of its own, fills the program binary cache and the driver's shader cache while
//! the app's frames pass through; the app's context then links the programs from the caches in
//! milliseconds. A driver that compiles inside the GL calls (Mesa's llvmpipe, although it
//! offers GL_KHR_parallel_shader_compile) would otherwise do it on the app's thread, for a
//! second or more. No GL call is made on a thread of the layer's own.

use crate::algorithm::params::Params;
use crate::gpu::opengl::gl_sources_id;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How long the layer waits for a build before it stops it and builds in the app's context.
const LIMIT: Duration = Duration::from_secs(60);

/// A build process of one view shape.
pub struct ProgramBuilder {
    child: Option<Child>,
    pub since: Instant,
    pub shape: (u32, u32, Params),
}

/// Where a build stands.
pub enum Built {
    Running,
    /// Ended: Ok with the time it took, or why it did not build.
    Ended(Result<Duration, String>),
}

/// The tool that came with the library (installed_files::tool_beside). Another build of it
/// refuses (its sources id differs).
fn tool() -> Option<PathBuf> {
    let file = crate::layer::installed_files::library_file()?;
    let path: &std::ffi::OsStr = std::os::unix::ffi::OsStrExt::from_bytes(file.to_bytes());
    crate::layer::installed_files::tool_beside(std::path::Path::new(path))
}

impl ProgramBuilder {
    /// Starts building the programs views of `internal_format`, `width` texels wide, need for
    /// `params`, on `driver` ("vendor | renderer | version" of the app's context).
    pub fn start(
        driver: &str,
        internal_format: u32,
        width: u32,
        params: &Params,
    ) -> Result<ProgramBuilder, String> {
        if crate::fault::hit("gl-program-process") {
            return Err("the build process could not start (fault point)".into());
        }
        let tool = tool().ok_or("no contrastxr tool beside the layer's library")?;
        let child = Command::new(&tool)
            .arg("gl-programs")
            .args(["--format", &format!("{internal_format:#06x}")])
            .args(["--width", &width.to_string()])
            .args(["--mode", params.mode.name()])
            .args(["--method", params.method.name()])
            .args(["--achromatic-boost", &params.achromatic_boost.to_string()])
            .args(["--luminance-cap", &params.luminance_cap.to_string()])
            .args(["--driver", driver])
            .args(["--sources", &format!("{:016x}", gl_sources_id())])
            // The driver's cache and the layer's follow the app's environment; a preloaded
            // library of the app's (an overlay, a recorder) has no business in the tool.
            .env_remove("LD_PRELOAD")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot run {}: {e}", tool.display()))?;
        Ok(ProgramBuilder {
            child: Some(child),
            since: Instant::now(),
            shape: (internal_format, width, params.clone()),
        })
    }

    /// Whether the build ended, without waiting; one past LIMIT is stopped.
    pub fn poll(&mut self) -> Built {
        let Some(child) = self.child.as_mut() else {
            return Built::Ended(Err("already ended".into()));
        };
        let status = match child.try_wait() {
            Ok(None) if self.since.elapsed() < LIMIT => return Built::Running,
            Ok(None) => {
                self.stop_and_reap();
                return Built::Ended(Err(format!("it ran past {} s", LIMIT.as_secs())));
            }
            Ok(Some(status)) => Ok(status),
            // An app that reaps every child (SIGCHLD ignored) took its status.
            Err(e) => Err(format!("its exit status is lost ({e})")),
        };
        let child = self.child.take().expect("checked above");
        Built::Ended(match status {
            Ok(s) if s.success() => Ok(self.since.elapsed()),
            Ok(s) => Err(format!("{s}: {}", last_line(child))),
            Err(e) => Err(e),
        })
    }

    /// Stops the build now (the session passes through or ends).
    pub fn stop(&self) {
        let Some(child) = &self.child else { return };
        let pid = child.id() as libc::pid_t;
        // SAFETY: siginfo_t is plain C data; all-zero is a valid value for waitid to fill.
        let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
        let flags = libc::WEXITED | libc::WNOHANG | libc::WNOWAIT;
        // SAFETY: waitid with WNOWAIT only looks: it reaps nothing. It fails (ECHILD) where
        // the app took the child's status (SIGCHLD ignored), whose pid may then name another
        // process: nothing is signalled then.
        if unsafe { libc::waitid(libc::P_PID, pid as libc::id_t, &mut info, flags) } != 0 {
            return;
        }
        // SAFETY: kill on the pid of our own child, running or not yet reaped, so the pid
        // names it and no other process.
        unsafe { libc::kill(pid, libc::SIGKILL) };
    }

    fn stop_and_reap(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

impl Drop for ProgramBuilder {
    fn drop(&mut self) {
        self.stop_and_reap();
    }
}

/// The last non-empty line the tool wrote to stderr (its reason), at most 300 bytes.
fn last_line(child: Child) -> String {
    use std::io::Read;
    let mut text = Vec::new();
    if let Some(mut err) = child.stderr {
        let _ = err.by_ref().take(64 * 1024).read_to_end(&mut text);
    }
    let text = String::from_utf8_lossy(&text);
    let line = text.lines().rev().find(|l| !l.trim().is_empty());
    line.unwrap_or("no message").chars().take(300).collect()
}
