//! A source thread's scheduling priority: below the app's threads and its graphics driver's.
//! Where the CPU is the bottleneck (a software GPU driver, a small machine), a new background
//! frame's decoding and blurring then waits for the app's frame work instead of slowing it;
//! on an idle core it runs as before.

/// The nice value added to a source thread (0 = the app's; 19 = the lowest).
const SOURCE_NICENESS: i32 = 5;

/// Lowers the calling thread's priority (Linux schedules each thread by its own nice value).
pub fn yield_to_the_app() {
    lower_this_thread(SOURCE_NICENESS);
}

/// Sets the calling thread's nice value to `niceness` (a thread of the layer's own).
pub fn lower_this_thread(niceness: i32) {
    // SAFETY: gettid has no preconditions; setpriority on this thread's own id only changes
    // its scheduling weight (failure, e.g. under a seccomp filter, leaves it as it was).
    unsafe {
        let tid = libc::gettid();
        libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, niceness);
    }
}
