//! The log's file (`log.rs` decides what the lines are; this keeps them): every file-system
//! operation of it (its folder made, the file opened, looked up, rotated, opened again, written)
//! runs on a thread of its own, `contrastxr-log-file`. The app's thread only hands that thread
//! stamped lines through a queue of [`QUEUE_LINES`], never waiting: a file system that hangs (a
//! network or FUSE mount), at the first open or at any line after it, holds the writer, never
//! the app. Lines the queue cannot take are dropped and counted, said once on stderr, and the
//! count is written in the file when the queue takes lines again. The writer ends after
//! [`IDLE`] without a line, and when told to at `xrDestroyInstance` ([`end_writer`]) once it
//! has written what was queued; the next line starts another: no thread of the layer's stays
//! once the app has stopped logging. The file stays open between writers, so the process holds
//! one descriptor of it throughout.
//!
//! The file is opened non-blocking, a regular file only, never through a symlink; it is capped
//! at [`MAX_BYTES`]: past that it becomes `layer.log.1` (replacing the previous one) and a new
//! file starts, so two files at most. At the process's exit the writer is given [`EXIT_WAIT`]
//! to write what waits.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::Mutex;
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

/// How long the writer waits for a line before it ends (the next line starts another).
const IDLE: Duration = Duration::from_millis(250);

/// What the writer is handed.
enum Job {
    /// A whole line, its newline included.
    Line(String),
    /// Answered once every line queued before it is written.
    Flush(SyncSender<()>),
    /// Ends the writer once the lines queued before it are written, unless more came after.
    End,
}

/// The running writer's queue and the process that started it (a forked child has no writer);
/// None when none runs. Lines, flushes and the end are queued only under this lock, which a
/// writer that ends takes to see its queue empty and clear it: nothing is queued to a writer
/// that ended, and a flush after it has nothing to wait for.
static WRITER: Mutex<Option<(SyncSender<Job>, u32)>> = Mutex::new(None);

fn writer() -> std::sync::MutexGuard<'static, Option<(SyncSender<Job>, u32)>> {
    WRITER.lock().unwrap_or_else(|p| p.into_inner())
}

/// The file as the last writer left it, open, for the next one.
static OPEN: Mutex<Option<std::fs::File>> = Mutex::new(None);

/// Why the file cannot be written has been said on stderr (once per process).
static SAID: AtomicBool = AtomicBool::new(false);

/// The app's side of the file: where it is, and what the queue dropped.
pub struct FileQueue {
    path: PathBuf,
    /// Writes a line on stderr alone.
    say: fn(&str),
    /// Lines dropped since the queue last took one.
    dropped: u64,
    /// The first drop has been said on stderr.
    said_behind: bool,
}

impl FileQueue {
    /// The file at `path`, written by a writer started at the first line (and again at a line
    /// after it ended); `say` writes a line on stderr alone, which the writer uses to say once
    /// why the file cannot be written.
    pub fn new(path: PathBuf, say: fn(&str)) -> FileQueue {
        static AT_EXIT: std::sync::Once = std::sync::Once::new();
        AT_EXIT.call_once(|| {
            // SAFETY: registers a function of the library's own, which stays mapped until the
            // process ends (the layer's library is RTLD_NODELETE; the tests' is the executable).
            unsafe { libc::atexit(flush_at_exit) };
        });
        FileQueue {
            path,
            say,
            dropped: 0,
            said_behind: false,
        }
    }

    /// Hands the writer `text` after `prefix` (its time and process), never waiting. Returns a
    /// line for stderr the first time the queue is full.
    pub fn write(&mut self, prefix: &str, text: &str) -> Option<String> {
        let mut writer = writer();
        if self.dropped > 0 {
            let n = self.dropped;
            let note =
                format!("{prefix}{n} lines dropped: the log file's system did not keep up\n");
            if !self.send(&mut writer, note) {
                self.dropped += 1;
                return None;
            }
            self.dropped = 0;
        }
        if self.send(&mut writer, format!("{prefix}{text}\n")) {
            return None;
        }
        self.dropped += 1;
        (!std::mem::replace(&mut self.said_behind, true)).then(|| {
            format!("log file behind: {QUEUE_LINES} lines wait for its file system (a stalled network or FUSE mount?); lines are dropped and counted until it takes them")
        })
    }

    /// Queues `line`, starting a writer when none runs in this process; false when the queue
    /// is full or no writer can start.
    fn send(&self, writer: &mut Option<(SyncSender<Job>, u32)>, line: String) -> bool {
        let pid = std::process::id();
        let mut job = Job::Line(line);
        if let Some((jobs, _)) = writer.as_ref().filter(|(_, at)| *at == pid) {
            match jobs.try_send(job) {
                Ok(()) => return true,
                Err(TrySendError::Full(_)) => return false,
                // It panicked: another starts.
                Err(TrySendError::Disconnected(back)) => job = back,
            }
        }
        let (jobs, queued) = sync_channel(QUEUE_LINES);
        let w = Writer {
            path: self.path.clone(),
            file: None,
            say: self.say,
        };
        let spawned = std::thread::Builder::new()
            .name("contrastxr-log-file".into())
            .spawn(move || w.run(queued));
        if spawned.is_err() {
            *writer = None;
            return false;
        }
        let sent = jobs.try_send(job).is_ok();
        *writer = Some((jobs, pid));
        sent
    }
}

/// Waits at most `limit` for the writer to write every line queued so far; false when it did
/// not in time.
pub fn flush(limit: Duration) -> bool {
    let since = Instant::now();
    let (done, answered) = sync_channel(1);
    let mut job = Job::Flush(done);
    loop {
        let writer = writer();
        let Some((jobs, _)) = writer.as_ref().filter(|(_, at)| *at == std::process::id()) else {
            // No writer: every line queued was written.
            return true;
        };
        match jobs.try_send(job) {
            Ok(()) => break,
            Err(TrySendError::Full(back)) if since.elapsed() < limit => job = back,
            Err(TrySendError::Full(_)) => return false,
            Err(TrySendError::Disconnected(_)) => return true,
        }
        drop(writer);
        std::thread::sleep(Duration::from_millis(1));
    }
    answered
        .recv_timeout(limit.saturating_sub(since.elapsed()))
        .is_ok()
}

/// Tells the writer to end once it has written the lines queued so far, without waiting (the
/// next line starts another): at `xrDestroyInstance`, so that no thread of the layer's stays
/// after the app's last instance.
pub fn end_writer() {
    if let Some((jobs, _)) = writer().as_ref() {
        let _ = jobs.try_send(Job::End);
    }
}

extern "C" fn flush_at_exit() {
    // A panic must not cross into libc's exit.
    let _ = std::panic::catch_unwind(|| flush(EXIT_WAIT));
}

/// The writer's side, on its own thread: the file.
struct Writer {
    path: PathBuf,
    file: Option<std::fs::File>,
    say: fn(&str),
}

impl Writer {
    fn run(mut self, jobs: Receiver<Job>) {
        let body = std::panic::AssertUnwindSafe(|| {
            let kept = OPEN.lock().unwrap_or_else(|p| p.into_inner()).take();
            self.file = kept.or_else(|| self.open());
            loop {
                let job = match jobs.recv_timeout(IDLE) {
                    Ok(Job::End) | Err(RecvTimeoutError::Timeout) => {
                        // Told to end, or idle: unless a job came meanwhile, it ends, seeing
                        // its queue empty under the writer's lock; the file is kept open for
                        // the next writer, which starts only once that lock is let go.
                        let mut writer = writer();
                        match jobs.try_recv() {
                            Ok(job) => job,
                            Err(_) => {
                                *OPEN.lock().unwrap_or_else(|p| p.into_inner()) = self.file.take();
                                *writer = None;
                                break;
                            }
                        }
                    }
                    Ok(job) => job,
                    Err(RecvTimeoutError::Disconnected) => break,
                };
                match job {
                    Job::Line(line) => self.write(&line),
                    Job::Flush(done) => drop(done.send(())),
                    Job::End => {}
                }
            }
        });
        // A panic ends the writer (the next line starts another).
        let _ = std::panic::catch_unwind(body);
    }

    /// The file, or None after saying once on stderr why it cannot be written.
    fn open(&mut self) -> Option<std::fs::File> {
        match open_file(&self.path) {
            Ok(f) => Some(f),
            Err(e) => {
                if !SAID.swap(true, Ordering::Relaxed) {
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
        // The old file is closed before the new one opens: one descriptor at any moment.
        if at_path.as_ref().is_some_and(|m| m.len() >= MAX_BYTES) {
            let _ = std::fs::rename(&self.path, rotated(&self.path));
            self.file = None;
            self.file = self.open();
        } else if !same {
            self.file = None;
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

    fn temp_dir(name: &str) -> crate::scratch::ScratchDir {
        crate::scratch::ScratchDir::new(name)
    }

    #[test]
    fn the_file_is_rotated_at_the_cap() {
        let dir = temp_dir("log-rotate");
        let path = dir.join("layer.log");
        let mut writer = Writer {
            file: None,
            path: path.clone(),
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

    /// The tests that use the process's writer, one at a time.
    fn one_writer() -> std::sync::MutexGuard<'static, ()> {
        static ONE: Mutex<()> = Mutex::new(());
        ONE.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn lines(queued: &Receiver<Job>) -> Vec<String> {
        queued
            .try_iter()
            .filter_map(|j| match j {
                Job::Line(l) => Some(l),
                Job::Flush(_) | Job::End => None,
            })
            .collect()
    }

    /// A writer that takes nothing (its file system hung): the queue takes QUEUE_LINES lines,
    /// then drops and counts the rest without waiting, says so once, and once the writer takes
    /// lines again the count comes first, then the line.
    #[test]
    fn a_full_queue_drops_and_counts_lines_without_waiting() {
        let _one = one_writer();
        let (jobs, queued) = sync_channel(QUEUE_LINES);
        *writer() = Some((jobs, std::process::id()));
        let mut queue = FileQueue {
            path: PathBuf::from("/nowhere/layer.log"),
            say: |line| panic!("said: {line}"),
            dropped: 0,
            said_behind: false,
        };
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
        let taken = lines(&queued);
        assert_eq!(taken.len(), QUEUE_LINES);
        assert_eq!(
            taken[QUEUE_LINES - 1],
            format!("T line {}\n", QUEUE_LINES - 1)
        );
        assert_eq!(queue.write("U ", "again"), None);
        assert_eq!(
            lines(&queued),
            [
                "U 5 lines dropped: the log file's system did not keep up\n",
                "U again\n"
            ]
        );
        *writer() = None;
    }

    /// The writer's threads of this process, by name.
    fn writers() -> usize {
        std::fs::read_dir("/proc/self/task")
            .unwrap()
            .flatten()
            .filter_map(|t| std::fs::read_to_string(t.path().join("comm")).ok())
            .filter(|n| n.trim() == "contrastxr-log-file")
            .count()
    }

    /// The descriptors of this process open on `path`.
    fn open_on(path: &Path) -> usize {
        std::fs::read_dir("/proc/self/fd")
            .unwrap()
            .flatten()
            .filter(|fd| std::fs::read_link(fd.path()).is_ok_and(|p| p == path))
            .count()
    }

    /// Waits up to 5 s for the writer to have ended; whether it did.
    fn ended() -> bool {
        let since = Instant::now();
        while (writer().is_some() || writers() > 0) && since.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(10));
        }
        writer().is_none() && writers() == 0
    }

    /// The writer writes the lines in order and ends when idle, or sooner when told to
    /// (`end_writer`, after the lines queued before, without waiting for them), and the next
    /// line starts another that appends to the file; the file stays open, once, between
    /// writers.
    #[test]
    fn the_writer_ends_when_idle_or_told_and_the_next_line_starts_another() {
        let _one = one_writer();
        let dir = temp_dir("log-idle");
        let path = dir.join("layer.log");
        let mut queue = FileQueue::new(path.clone(), |line| panic!("said: {line}"));
        assert_eq!(queue.write("A ", "one"), None);
        assert_eq!(queue.write("A ", "two"), None);
        assert!(flush(Duration::from_secs(5)));
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "A one\nA two\n");
        assert_eq!(open_on(&path), 1);
        assert!(ended(), "the writer did not end when idle");
        assert_eq!(open_on(&path), 1, "the file was closed with the writer");
        assert_eq!(queue.write("B ", "three"), None);
        let t = Instant::now();
        end_writer();
        assert!(ended(), "the writer did not end when told");
        assert!(
            t.elapsed() < IDLE,
            "it ended only when idle: {:?}",
            t.elapsed()
        );
        assert_eq!(open_on(&path), 1, "the file was closed with the writer");
        assert_eq!(queue.write("C ", "four"), None);
        assert!(flush(Duration::from_secs(5)));
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "A one\nA two\nB three\nC four\n");
        assert_eq!(open_on(&path), 1);
        end_writer();
        assert!(ended());
        *OPEN.lock().unwrap() = None;
        std::fs::remove_dir_all(&dir).unwrap();
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
