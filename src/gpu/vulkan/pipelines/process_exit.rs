//! The pipeline threads against the end of the host process. An app may exit (or unload the
//! layer) without destroying its session: its `exit` then runs the driver's static destructors
//! (lavapipe's LLVM among them) while a pipeline thread may be compiling or calling the app's
//! device. At exit, or when the layer's library is unloaded, the handler registered here stops
//! every pipeline thread from starting more work and waits (boundedly) for the work in progress.

use std::sync::{Condvar, Mutex, MutexGuard, Once, OnceLock};
use std::time::{Duration, Instant};

/// The longest the process's exit waits for a build in progress (a compile on lavapipe takes
/// up to a few seconds on a loaded machine).
const EXIT_WAIT: Duration = Duration::from_secs(20);

#[derive(Default)]
struct Work {
    /// Builds in progress on pipeline threads.
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

/// What the exit runs first, with its deadline: each waits for work of the layer's own still
/// running in a driver (gpu/vulkan/frame/warm_up.rs's left-over compiles).
fn exit_waits() -> MutexGuard<'static, Vec<fn(Instant)>> {
    static WAITS: Mutex<Vec<fn(Instant)>> = Mutex::new(Vec::new());
    WAITS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Has the exit run `wait` (once per call of this) before it waits for the builds.
pub fn on_exit(wait: fn(Instant)) {
    watch();
    exit_waits().push(wait);
}

/// Registers the exit handler (once per process, on the first pipeline thread).
pub fn watch() {
    static REGISTERED: Once = Once::new();
    REGISTERED.call_once(|| {
        // SAFETY: at_exit is a plain function of this library; glibc's atexit runs it at exit
        // or when this library is unloaded, whichever comes first.
        unsafe { libc::atexit(at_exit) };
    });
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

extern "C" fn at_exit() {
    let deadline = Instant::now() + EXIT_WAIT;
    lock().exiting = true;
    let waits = std::mem::take(&mut *exit_waits());
    waits.into_iter().for_each(|wait| wait(deadline));
    let mut w = lock();
    while w.busy > 0 {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return;
        }
        w = match work().1.wait_timeout(w, left) {
            Ok((w, _)) => w,
            Err(p) => p.into_inner().0,
        };
    }
}
