//! Samples of the client's resident memory, heap in use and open file descriptors (the soak
//! and session cycle tests read them from the report).

use serde::Serialize;

/// The process's resident memory, heap in use and open file descriptors at one moment.
#[derive(Serialize, Debug, Default, Clone)]
pub struct Sample {
    pub frames: u32,
    pub rss_kb: u64,
    /// Bytes handed out by malloc and not freed, over every arena, in KiB (glibc's mallinfo2:
    /// `uordblks + hblkhd`). A leak grows it by what it leaks, where resident memory may not
    /// grow at all while the leaked blocks fill the holes of freed ones.
    pub heap_kb: u64,
    pub fds: u64,
}

impl Sample {
    pub fn now(frames: u32) -> Sample {
        let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
        let pages: u64 = statm
            .split_whitespace()
            .nth(1)
            .and_then(|v| v.parse().ok())
            .unwrap_or(0);
        // SAFETY: sysconf has no preconditions.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(0) as u64;
        let fds = std::fs::read_dir("/proc/self/fd").map_or(0, |d| d.count() as u64);
        // SAFETY: mallinfo2 has no preconditions (it takes each arena's lock in turn).
        let heap = unsafe { libc::mallinfo2() };
        Sample {
            frames,
            rss_kb: pages * page / 1024,
            heap_kb: ((heap.uordblks + heap.hblkhd) / 1024) as u64,
            fds,
        }
    }
}
