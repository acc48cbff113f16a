//! The log's file (`log.rs` decides what the lines are; this keeps them): every file-system
//! operation of it (its folder made, the file opened, looked up, rotated, opened again, written)
//! runs on a thread of its own, `contrastxr-log-file`. The app's thread only hands that thread
//! stamped lines through a queue of [`QUEUE_LINES`], never waiting: a file system that hangs (a
//! network or FUSE mount), at the first open or at any line after it, holds the writer, never
//! the app. Lines the queue cannot take are dropped and counted, said once on stderr, and the
//! count is written in the file when the queue takes lines again.
//!
//! The file is opened non-blocking, a regular file only, never through a symlink; it is capped
//! at [`MAX_BYTES`]: past that it becomes `layer.log.1` (replacing the previous one) and a new
//! file starts, so two files at most. At the process's exit the writer is given [`EXIT_WAIT`]
//! to write what waits.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Lines waiting for the writer; past this many, lines are dropped and counted.
pub const QUEUE_LINES: usize = 256;

/// Size past which the log file is rotated.
pub const MAX_BYTES: u64 = 1 << 20;

/// How long the process's exit waits at most for lines the writer has not written yet.
pub const EXIT_WAIT: Duration = Duration::from_millis(250);

/// The rotated file beside `path`: `layer.log.1`.
pub fn rotated(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".1");
    PathBuf::from(name)
}

/// What the writer is handed.
enum Job {
    /// A whole line, its newline included.
    Line(String),
    /// Answered once every line queued before it is written.
    Flush(SyncSender<()>),
}

/// The app's side of the file: the queue to its writer, and what the queue dropped.
pub struct FileQueue {
    jobs: SyncSender<Job>,
    /// Lines dropped since the queue last took one.
    dropped: u64,
    /// The first drop has been said on stderr.
    said_behind: bool,
}

/// The writer's queue, for [`flush`] (which must not wait for the log's lock), and the process
/// that started it (a forked child has no writer).
static JOBS: OnceLock<(SyncSender<Job>, u32)> = OnceLock::new();

impl FileQueue {
    /// Starts the writer of the file at `path` (it opens the file first); `say` writes a line
    /// on stderr alone, which the writer uses to say once why the file cannot be written. Err
    /// when no thread can start.
    pub fn start(path: PathBuf, say: fn(&str)) -> Result<FileQueue, String> {
        let (jobs, queued) = sync_channel(QUEUE_LINES);
        let writer = Writer {
            path,
            file: None,
            said: false,
            say,
        };
        std::thread::Builder::new()
            .name("contrastxr-log-file".into())
            .spawn(move || writer.run(queued))
            .map_err(|e| format!("no thread for the log file: {e}"))?;
        if JOBS.set((jobs.clone(), std::process::id())).is_ok() {
            // SAFETY: registers a function of the library's own, which stays mapped until the
            // process ends (the layer's library is RTLD_NODELETE; the tests' is the executable).
            unsafe { libc::atexit(flush_at_exit) };
        }
        Ok(FileQueue::on(jobs))
    }

    fn on(jobs: SyncSender<Job>) -> FileQueue {
        FileQueue {
            jobs,
            dropped: 0,
            said_behind: false,
        }
    }

    /// Hands the writer `text` after `prefix` (its time and process), never waiting. Returns a
    /// line for stderr the first time the queue is full.
    pub fn write(&mut self, prefix: &str, text: &str) -> Option<String> {
        if self.dropped > 0 {
            let n = self.dropped;
            let note =
                format!("{prefix}{n} lines dropped: the log file's system did not keep up\n");
            if !self.try_send(note) {
                self.dropped += 1;
                return None;
            }
            self.dropped = 0;
        }
        if self.try_send(format!("{prefix}{text}\n")) {
            return None;
        }
        self.dropped += 1;
        (!std::mem::replace(&mut self.said_behind, true)).then(|| {
            format!("log file behind: {QUEUE_LINES} lines wait for its file system (a stalled network or FUSE mount?); lines are dropped and counted until it takes them")
        })
    }

    fn try_send(&self, line: String) -> bool {
        match self.jobs.try_send(Job::Line(line)) {
            Ok(()) => true,
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => false,
        }
    }
}

/// Waits at most `limit` for the writer to write every line queued so far; false when it did
/// not in time (or there is no writer).
pub fn flush(limit: Duration) -> bool {
    let Some((jobs, pid)) = JOBS.get() else {
        return false;
    };
    if *pid != std::process::id() {
        return false;
    }
    let since = Instant::now();
    let (done, answered) = sync_channel(1);
    let mut job = Job::Flush(done);
    loop {
        match jobs.try_send(job) {
            Ok(()) => break,
            Err(TrySendError::Full(back)) if since.elapsed() < limit => {
                job = back;
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(_) => return false,
        }
    }
    answered
        .recv_timeout(limit.saturating_sub(since.elapsed()))
        .is_ok()
}

extern "C" fn flush_at_exit() {
    // A panic must not cross into libc's exit.
    let _ = std::panic::catch_unwind(|| flush(EXIT_WAIT));
}

/// The writer's side, on its own thread: the file and whether its failure was said.
struct Writer {
    path: PathBuf,
    file: Option<std::fs::File>,
    said: bool,
    say: fn(&str),
}

impl Writer {
    fn run(mut self, jobs: Receiver<Job>) {
        let body = std::panic::AssertUnwindSafe(|| {
            self.file = self.open();
            for job in jobs {
                match job {
                    Job::Line(line) => self.write(&line),
                    Job::Flush(done) => drop(done.send(())),
                }
            }
        });
        // A panic ends the writer: the queue then takes no line, and lines are dropped.
        let _ = std::panic::catch_unwind(body);
    }

    /// The file, or None after saying once on stderr why it cannot be written.
    fn open(&mut self) -> Option<std::fs::File> {
        match open_file(&self.path) {
            Ok(f) => Some(f),
            Err(e) => {
                if !std::mem::replace(&mut self.said, true) {
                    (self.say)(&format!("log file not written: {e}"));
                }
                None
            }
        }
    }

    /// Rotates when the file at the path is over the cap, and follows a rotation another
    /// process did (the path then names a different file than ours).
    fn keep_in_bounds(&mut self) {
        use std::os::unix::fs::MetadataExt;
        let ours = self.file.as_ref().and_then(|f| f.metadata().ok());
        let at_path = crate::user_file::metadata(&self.path).ok();
        let same = matches!((&ours, &at_path), (Some(a), Some(b)) if a.ino() == b.ino() && a.dev() == b.dev());
        if at_path.as_ref().is_some_and(|m| m.len() >= MAX_BYTES) {
            let _ = std::fs::rename(&self.path, rotated(&self.path));
            self.file = self.open();
        } else if !same {
            self.file = self.open();
        }
    }

    fn write(&mut self, line: &str) {
        self.keep_in_bounds();
        if let Some(f) = self.file.as_mut() {
            let _ = f.write_all(line.as_bytes());
        }
    }
}

/// Opens the log file for appending without blocking (a FIFO there fails at once), only a
/// regular file and never through a symlink at its last component; the error names the path.
fn open_file(path: &Path) -> Result<std::fs::File, String> {
    use std::os::unix::fs::OpenOptionsExt;
    crate::user_file::stall();
    let dir = path.parent().unwrap_or(Path::new("/"));
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC | libc::O_NOFOLLOW)
        .open(path)
        .map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    match file.metadata() {
        Ok(m) if m.is_file() => Ok(file),
        Ok(_) => Err(format!("{} is not a regular file", path.display())),
        Err(e) => Err(format!("cannot read {}: {e}", path.display())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("contrastxr-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn the_file_is_rotated_at_the_cap() {
        let dir = temp_dir("log-rotate");
        let path = dir.join("layer.log");
        let mut writer = Writer {
            file: None,
            path: path.clone(),
            said: false,
            say: |line| panic!("said: {line}"),
        };
        writer.file = writer.open();
        let line = format!("{}\n", "x".repeat(1000));
        for _ in 0..1100 {
            writer.write(&line);
        }
        let size = |p: &Path| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
        let (current, old) = (size(&path), size(&rotated(&path)));
        assert!((MAX_BYTES..MAX_BYTES + 1100).contains(&old), "{old}");
        assert!(current > 0 && current < MAX_BYTES, "{current}");
        // Every line is kept across the two files.
        assert_eq!((current + old) as usize, 1100 * line.len());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A writer that takes nothing (its file system hung): the queue takes QUEUE_LINES lines,
    /// then drops and counts the rest without waiting, says so once, and once the writer takes
    /// lines again the count comes first, then the line.
    #[test]
    fn a_full_queue_drops_and_counts_lines_without_waiting() {
        let (jobs, queued) = sync_channel(QUEUE_LINES);
        let mut queue = FileQueue::on(jobs);
        let t = Instant::now();
        let said: Vec<String> = (0..QUEUE_LINES + 5)
            .filter_map(|i| queue.write("T ", &format!("line {i}")))
            .collect();
        assert!(
            t.elapsed() < Duration::from_millis(100),
            "{:?}",
            t.elapsed()
        );
        assert_eq!(said.len(), 1, "{said:?}");
        assert!(
            said[0].contains("lines are dropped and counted"),
            "{said:?}"
        );
        let lines: Vec<String> = queued
            .try_iter()
            .filter_map(|j| match j {
                Job::Line(l) => Some(l),
                Job::Flush(_) => None,
            })
            .collect();
        assert_eq!(lines.len(), QUEUE_LINES);
        assert_eq!(
            lines[QUEUE_LINES - 1],
            format!("T line {}\n", QUEUE_LINES - 1)
        );
        assert_eq!(queue.write("U ", "again"), None);
        let next: Vec<String> = queued
            .try_iter()
            .filter_map(|j| match j {
                Job::Line(l) => Some(l),
                Job::Flush(_) => None,
            })
            .collect();
        assert_eq!(
            next,
            [
                "U 5 lines dropped: the log file's system did not keep up\n",
                "U again\n"
            ]
        );
    }

    #[test]
    fn an_unwritable_log_file_is_named_with_why() {
        let dir = temp_dir("log-open");
        let under_dev_null = Path::new("/dev/null/contrastxr/layer.log");
        let e = open_file(under_dev_null).unwrap_err();
        assert!(
            e.contains("/dev/null/contrastxr") && e.contains("Not a directory"),
            "{e}"
        );
        // A FIFO nobody reads fails at once instead of blocking the open.
        let fifo = dir.join("fifo.log");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        assert!(open_file(&fifo).unwrap_err().contains("fifo.log"));
        // A symlink at the last component is not followed.
        let target = dir.join("elsewhere.log");
        let link = dir.join("link.log");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        assert!(open_file(&link).unwrap_err().contains("link.log"));
        assert!(!target.exists());
        assert!(open_file(&dir.join("layer.log")).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
