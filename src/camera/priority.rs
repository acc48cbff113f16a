//! A source thread's scheduling priority: below the app's threads and its graphics driver's.
//! Where the CPU is the bottleneck (a software GPU driver, a small machine), a new background
//! frame's decoding and blurring then waits for the app's frame work instead of slowing it;
//! on an idle core it runs as before.

/// The nice value added to a source thread (0 = as the app's thread that made it).
const SOURCE_NICENESS: i32 = 5;

/// The largest nice value Linux knows (the lowest priority).
const LOWEST: i32 = 19;

/// Lowers the calling thread's priority (Linux schedules each thread by its own nice value).
pub fn yield_to_the_app() {
    lower_this_thread(SOURCE_NICENESS);
}

/// Adds `by` to the calling thread's nice value (a thread of the layer's own, which started
/// with the nice value of the app's thread that made it), up to the lowest priority: relative,
/// so that under an app started with `nice` the thread still runs below it, never above.
pub fn lower_this_thread(by: i32) {
    // SAFETY: gettid has no preconditions; errno is this thread's own; getpriority and
    // setpriority on this thread's own id only read or change its scheduling weight (failure,
    // e.g. under a seccomp filter, leaves it as it was).
    unsafe {
        let tid = libc::gettid() as libc::id_t;
        // -1 is also a nice value: errno tells a failure apart.
        *libc::__errno_location() = 0;
        let now = libc::getpriority(libc::PRIO_PROCESS, tid);
        if now == -1 && *libc::__errno_location() != 0 {
            return;
        }
        libc::setpriority(libc::PRIO_PROCESS, tid, (now + by).min(LOWEST));
    }
}
