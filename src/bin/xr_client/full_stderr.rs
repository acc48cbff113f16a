//! `--stderr-full`: the process's stderr becomes a pipe that is full and that nobody reads, as
//! for an app whose stderr goes to a pipe its parent never drains. A write to it blocks.

/// Makes fd 2 a full pipe; returns the original stderr (None if that could not be done).
pub fn install() -> Option<i32> {
    let mut fds = [0; 2];
    // SAFETY: a valid array for the two descriptors; fd 2 is duplicated, not closed.
    let saved = unsafe {
        if libc::pipe(fds.as_mut_ptr()) != 0 {
            return None;
        }
        libc::dup(2)
    };
    // SAFETY: fds[1] is ours; non-blocking only while it is filled.
    unsafe { libc::fcntl(fds[1], libc::F_SETFL, libc::O_NONBLOCK) };
    let block = [b'#'; 4096];
    // SAFETY: writes from a valid buffer to our own pipe, until it is full.
    while unsafe { libc::write(fds[1], block.as_ptr().cast(), block.len()) } > 0 {}
    // SAFETY: back to blocking, as an app's stderr is; then it replaces fd 2. The read end
    // stays open (never read), so a write blocks rather than failing.
    unsafe {
        libc::fcntl(fds[1], libc::F_SETFL, 0);
        libc::dup2(fds[1], 2);
        libc::close(fds[1]);
    }
    Some(saved)
}

/// Gives fd 2 back to the original stderr (for the report).
pub fn restore(saved: i32) {
    // SAFETY: saved is the duplicate made by install.
    unsafe {
        libc::dup2(saved, 2);
        libc::close(saved);
    }
}
