//! The layer's driver work against the end of the host process. An app may exit (or unload
//! the layer) while a thread of the layer compiles in the driver or calls the app's device: a
//! Vulkan pipeline build, a warm-up compile left running at a session's end, an OpenGL program
//! build. The exit then runs the driver's destructors (llvmpipe's LLVM among them) under that
//! work. The exit handler here stops every such thread from starting more work and waits
//! (boundedly) for the work in progress.
//!
//! It must run before the driver's destructors. glibc runs exit handlers newest first, and a
//! compiler registers destructors of its own lazily, during compiles that start after the
//! layer's handler was registered. So the wait runs first of all in a thread-local destructor
//! of the process's main thread, which glibc's `exit` runs before any exit handler; the
//! `atexit` handler is the fallback for an exit from another thread and for an unloaded
//! library. One side effect: a main thread that ends with `pthread_exit` while the process
//! goes on leaves the layer building nothing more (its frames pass through).

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, Once, OnceLock};
use std::time::{Duration, Instant};

/// The longest the process's exit waits for the builds in progress. Each stops at its next
/// step once the exit began (a Vulkan pipeline, an OpenGL program, the programs' first run), so
/// the wait is for one step: up to a few seconds on lavapipe or llvmpipe, more under heavy load.
const EXIT_WAIT: Duration = Duration::from_secs(20);

#[derive(Default)]
struct Work {
    /// Builds in progress on the layer's threads (Vulkan pipelines, OpenGL programs).
    busy: u32,
    /// The process is exiting: no build may start.
    exiting: bool,
}

fn work() -> &'static (Mutex<Work>, Condvar) {
    static WORK: OnceLock<(Mutex<Work>, Condvar)> = OnceLock::new();
    WORK.get_or_init(Default::default)
}

fn lock() -> MutexGuard<'static, Work> {
    // Plain counters: a panic while holding the lock leaves them usable.
    work().0.lock().unwrap_or_else(|p| p.into_inner())
}

/// Waits until the deadline at most; whether there was anything to wait for.
pub type ExitWait = fn(Instant) -> bool;

/// What the exit runs first, with its deadline: each waits for work of the layer's own still
/// running in a driver (gpu/vulkan/frame/warm_up.rs's left-over compiles).
fn exit_waits() -> MutexGuard<'static, Vec<ExitWait>> {
    static WAITS: Mutex<Vec<ExitWait>> = Mutex::new(Vec::new());
    WAITS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Has the exit run `wait` (once per call of this) before it waits for the builds.
pub fn on_exit(wait: ExitWait) {
    watch();
    exit_waits().push(wait);
}

/// Registers the exit handler (once per process) and, called on the main thread, its
/// thread-local twin. Called on an app's thread before driver work of the layer starts.
pub fn watch() {
    static REGISTERED: Once = Once::new();
    REGISTERED.call_once(|| {
        // SAFETY: at_exit is a plain function of this library; glibc's atexit runs it at exit
        // or when this library is unloaded, whichever comes first.
        unsafe { libc::atexit(at_exit) };
    });
    if is_main_thread() {
        // try_with: an app may end its session from an exit handler, after the main thread's
        // destructors ran (the handler has then run already).
        let _ = MAIN_THREAD_EXIT.try_with(|_| ());
    }
}

/// Dropped when the main thread ends: at the process's exit, before every exit handler.
struct MainThreadExit;

impl Drop for MainThreadExit {
    fn drop(&mut self) {
        at_exit();
    }
}

thread_local! {
    static MAIN_THREAD_EXIT: MainThreadExit = const { MainThreadExit };
}

fn is_main_thread() -> bool {
    // SAFETY: gettid and getpid have no preconditions.
    unsafe { libc::gettid() == libc::getpid() }
}

/// A build in progress: counted from [`Busy::begin`] until dropped, also when the build
/// panics (a count left raised would make every later exit wait the full bound).
pub struct Busy(());

impl Busy {
    /// A build may start: None once the process is exiting.
    pub fn begin() -> Option<Busy> {
        let mut w = lock();
        if w.exiting {
            return None;
        }
        w.busy += 1;
        Some(Busy(()))
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        lock().busy -= 1;
        work().1.notify_all();
    }
}

/// Whether the process is exiting (a build checks before it touches the app's device).
pub fn exiting() -> bool {
    lock().exiting
}

/// Stops new work and waits for the work in progress; says how long when it waited (the app's
/// exit took that much longer). Runs at most twice per exit (the main thread's destructor, then
/// the handler), against one deadline from the first run and with one line: a second run finds
/// nothing left, or the deadline past (the driver's destructors may have run by then anyway).
extern "C" fn at_exit() {
    // Called by glibc: a panic must not unwind into it.
    let _ = std::panic::catch_unwind(wait_for_work);
}

fn wait_for_work() {
    static FIRST_RUN: OnceLock<Instant> = OnceLock::new();
    static SAID: AtomicBool = AtomicBool::new(false);
    let started = *FIRST_RUN.get_or_init(Instant::now);
    let deadline = started + EXIT_WAIT;
    lock().exiting = true;
    let waits = std::mem::take(&mut *exit_waits());
    let mut waited = lock().busy > 0;
    for wait in waits {
        waited |= wait(deadline);
    }
    let mut w = lock();
    while w.busy > 0 && Instant::now() < deadline {
        let left = deadline.saturating_duration_since(Instant::now());
        w = match work().1.wait_timeout(w, left) {
            Ok((w, _)) => w,
            Err(p) => p.into_inner().0,
        };
    }
    let left_running = w.busy;
    drop(w);
    if waited && !SAID.swap(true, Ordering::Relaxed) {
        let _ = writeln!(
            std::io::stderr(),
            "{}",
            exit_line(started.elapsed(), left_running)
        );
    }
}

/// The one line of an exit that waited. Plain stderr, never a panic: the layer's log may
/// already be shut down this late.
fn exit_line(waited: Duration, left_running: u32) -> String {
    let ms = waited.as_millis();
    let mut line = format!(
        "contrastxr: the app's exit waited {ms} ms for shader builds still running in the driver"
    );
    if left_running > 0 {
        line += &format!(
            " and went on with {left_running} still running ({} s at most)",
            EXIT_WAIT.as_secs()
        );
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exit's one line says when it went on with builds still running, and only then.
    #[test]
    fn the_exit_line_says_what_it_left_running() {
        let done = exit_line(Duration::from_millis(812), 0);
        assert_eq!(
            done,
            "contrastxr: the app's exit waited 812 ms for shader builds still running in the driver"
        );
        let given_up = exit_line(EXIT_WAIT, 1);
        assert!(
            given_up.starts_with("contrastxr: the app's exit waited 20000 ms"),
            "{given_up}"
        );
        assert!(
            given_up.ends_with("and went on with 1 still running (20 s at most)"),
            "{given_up}"
        );
    }
}
