//! The layer's log: start-up lines (on or off, the config file, every setting with its origin)
//! and a few per session, then only changes and warnings, each once. Lines go to
//! stderr and to `$XDG_STATE_HOME/contrastxr/layer.log` (default `~/.local/state`), each with
//! an RFC 3339 UTC timestamp and the process id; `log_file.rs` keeps the file (two files at
//! most, each capped). The first line a process writes is a [`LOADED`] marker, which is how
//! `contrastxr log` finds the last app's lines. `CONTRASTXR_LOG=debug` adds debug lines.
//!
//! Logging never blocks an app's call: a line stderr cannot take at once (a pipe read slowly,
//! or by nobody) waits in a bounded backlog that a thread of the log's own writes in order;
//! past [`BACKLOG_LINES`] lines are dropped and counted. The file is written by a thread of its
//! own, which does every file-system operation (open, look-up, rotation, write): the app's
//! thread only queues the line, so a log folder on a hung file system (a network or FUSE
//! mount) never holds it. A log file that cannot be written is said once on stderr.

use std::collections::HashSet;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender};
use std::sync::{Mutex, OnceLock};
use std::time::{SystemTime, UNIX_EPOCH};

use super::log_file::FileQueue;

/// Lines waiting for a slow stderr; past this many, lines are dropped and counted.
pub const BACKLOG_LINES: usize = 256;

/// The file-only line each process writes first: `[pid N] layer loaded into EXE`.
pub const LOADED: &str = "layer loaded into ";
/// The line each session writes at xrCreateSession, then the binding's API ("Vulkan",
/// "OpenGL (Xlib)", "OpenGL (EGL)", ...) and whether the layer enhances it:
/// `graphics API of this session: OpenGL (Xlib), enhanced` or `..., passed through`.
pub const GRAPHICS_API: &str = "graphics API of this session: ";
/// The line when frames begin to pass through for a cause that may pass (the app's OpenGL
/// context current on another thread), after the cause: `WHY: this frame passes through ...`.
pub const TRIES_AGAIN: &str = "this frame passes through untouched; the layer tries again";
/// The lines of the layer's GPU time per frame, once a minute and at the session's end:
/// `GPU time of the layer's work per frame over the last 60 s: median ...` (`over the
/// session: ...`).
pub const GPU_TIME: &str = "GPU time of the layer's work per frame over ";
/// The line when a try succeeds after such frames: `enhancing again after N frames ...`.
pub const ENHANCING_AGAIN: &str = "enhancing again after";

struct Log {
    /// The file's queue to its writer; None without a file.
    file: Option<FileQueue>,
    seen: HashSet<String>,
    debug: bool,
    /// Lines stderr could not take without blocking, not yet reported there.
    dropped: u64,
}

/// `$XDG_STATE_HOME/contrastxr/layer.log` (default `~/.local/state/...`).
#[cfg(not(test))]
pub fn path() -> Option<PathBuf> {
    if super::elevated::elevated() {
        return None; // Its environment names the folder: not to be written with privileges.
    }
    let state = std::env::var_os("XDG_STATE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/state")))?;
    Some(state.join("contrastxr").join("layer.log"))
}

/// Unit tests log to stderr only: written to the user's file, their lines would make
/// `contrastxr log` and `doctor` name a test binary as the last app.
#[cfg(test)]
pub fn path() -> Option<PathBuf> {
    None
}

/// Days since 1970-01-01 to (year, month, day) in the proleptic Gregorian calendar
/// (Howard Hinnant's `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

/// `time` as RFC 3339 in UTC with milliseconds: `2026-11-22T19:04:05.123Z`.
pub fn rfc3339(time: SystemTime) -> String {
    let since = time.duration_since(UNIX_EPOCH).unwrap_or_default();
    let secs = since.as_secs() as i64;
    let (year, month, day) = civil_from_days(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}.{:03}Z",
        s / 3600,
        s / 60 % 60,
        s % 60,
        since.subsec_millis()
    )
}

/// The process's log, made at its first line.
static LOG: OnceLock<Mutex<Log>> = OnceLock::new();

fn log() -> &'static Mutex<Log> {
    LOG.get_or_init(|| {
        let mut log = Log {
            file: None,
            seen: HashSet::new(),
            debug: std::env::var("CONTRASTXR_LOG").is_ok_and(|v| v == "debug"),
            dropped: 0,
        };
        log.file = path().map(|p| FileQueue::new(p, say_on_stderr));
        let exe = std::env::current_exe()
            .map_or("an unknown program".into(), |p| p.display().to_string());
        write_file(&mut log, &format!("{LOADED}{exe}"));
        Mutex::new(log)
    })
}

/// Queues the line for the file's writer (never waiting), and says on stderr when the queue
/// first drops lines.
fn write_file(log: &mut Log, line: &str) {
    let Some(file) = log.file.as_mut() else {
        return;
    };
    let prefix = format!(
        "{} [pid {}] ",
        rfc3339(SystemTime::now()),
        std::process::id()
    );
    if let Some(behind) = file.write(&prefix, line) {
        write_stderr(log, &behind);
    }
}

/// A line on stderr alone: the file's writer says with it why the file cannot be written.
fn say_on_stderr(line: &str) {
    write_stderr(&mut lock(), line);
}

/// Writes `bytes` to `fd` only if that cannot block: poll first, and at most `PIPE_BUF` bytes,
/// which a pipe that polls writable takes whole. False when nothing was written.
fn write_now(fd: i32, bytes: &[u8]) -> bool {
    let bytes = &bytes[..bytes.len().min(libc::PIPE_BUF)];
    let mut poll = libc::pollfd {
        fd,
        events: libc::POLLOUT,
        revents: 0,
    };
    // SAFETY: one valid pollfd, and no waiting (timeout 0).
    let ready = unsafe { libc::poll(&mut poll, 1, 0) } == 1 && poll.revents == libc::POLLOUT;
    // SAFETY: a valid buffer of `len` bytes; fd is only written, never closed here.
    ready && unsafe { libc::write(fd, bytes.as_ptr().cast(), bytes.len()) } > 0
}

/// Lines stderr could not take at once, for the log's writer thread.
static BACKLOG: OnceLock<Option<SyncSender<Vec<u8>>>> = OnceLock::new();
/// How many lines of the backlog are not yet written.
static WAITING: AtomicUsize = AtomicUsize::new(0);

/// The backlog, its writer thread started at the first line stderr could not take (the thread
/// may block on stderr for as long as its reader makes it; the app never does).
fn backlog() -> Option<&'static SyncSender<Vec<u8>>> {
    BACKLOG
        .get_or_init(|| {
            let (lines, rx) = sync_channel::<Vec<u8>>(BACKLOG_LINES);
            let writer = move || {
                for bytes in rx {
                    let _ = std::io::stderr().write_all(&bytes);
                    WAITING.fetch_sub(1, Ordering::SeqCst);
                }
            };
            let spawned = std::thread::Builder::new()
                .name("contrastxr-log".into())
                .spawn(writer);
            spawned.ok().map(|_| lines)
        })
        .as_ref()
}

/// `bytes` to stderr now when no line waits before them and it cannot block; else into the
/// backlog, in order. False when the backlog is full (the line is lost).
fn send_to_stderr(bytes: Vec<u8>) -> bool {
    if WAITING.load(Ordering::SeqCst) == 0 && write_now(2, &bytes) {
        return true;
    }
    let Some(lines) = backlog() else {
        return false;
    };
    WAITING.fetch_add(1, Ordering::SeqCst);
    let sent = lines.try_send(bytes).is_ok();
    if !sent {
        WAITING.fetch_sub(1, Ordering::SeqCst);
    }
    sent
}

/// One line to stderr (now, or through the backlog), or dropped and counted when the backlog
/// is full.
fn write_stderr(log: &mut Log, line: &str) {
    if log.dropped > 0 {
        let said = format!(
            "contrastxr: {} lines not written: stderr would have blocked\n",
            log.dropped
        );
        if !send_to_stderr(said.into_bytes()) {
            log.dropped += 1;
            return;
        }
        log.dropped = 0;
    }
    if !send_to_stderr(format!("contrastxr: {line}\n").into_bytes()) {
        log.dropped += 1;
    }
}

fn write_line(log: &mut Log, line: &str) {
    write_stderr(log, line);
    write_file(log, line);
}

/// The log, also after a panic while it was held (its state is a file handle and a set of
/// keys: never half-changed in a way that matters).
fn lock() -> std::sync::MutexGuard<'static, Log> {
    log().lock().unwrap_or_else(|p| p.into_inner())
}

/// Makes a panic in the layer's code one line of this log instead of the default report on
/// stderr (a backtrace, written blocking): every panic is caught at the layer's boundary, which
/// says what happened to the session; the app never waits for stderr. The hook is the layer
/// library's own (it has its own copy of std), never the app's.
pub fn quiet_panics() {
    static SET: std::sync::Once = std::sync::Once::new();
    SET.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            // Only a log already made, and not held (a panic inside the log's own code): the
            // line is left out rather than waited for.
            if let Some(Ok(mut log)) = LOG.get().map(Mutex::try_lock) {
                write_line(&mut log, &format!("internal panic (caught): {info}"));
            }
        }));
    });
}

/// Logs a line unconditionally (startup, state changes).
pub fn info(line: &str) {
    write_line(&mut lock(), line);
}

/// Logs a line the first time `key` is seen in this process; per-frame conditions use this.
pub fn once(key: &str, line: &str) {
    let mut log = lock();
    if log.seen.insert(key.to_string()) {
        write_line(&mut log, line);
    }
}

/// Whether a line was logged under `key` with [`once`] in this process.
#[cfg(test)]
pub fn said_once(key: &str) -> bool {
    lock().seen.contains(key)
}

pub fn debug(line: &str) {
    let mut log = lock();
    if log.debug {
        write_line(&mut log, line);
    }
}

/// One line of the log file, split into its parts; None for a line of another shape.
pub struct Line<'a> {
    pub time: &'a str,
    pub pid: u32,
    pub text: &'a str,
}

pub fn parse_line(line: &str) -> Option<Line<'_>> {
    let (time, rest) = line.split_once(" [pid ")?;
    let (pid, text) = rest.split_once("] ")?;
    Some(Line {
        time,
        pid: pid.parse().ok()?,
        text,
    })
}

/// The lines of the last process that loaded the layer, from its [`LOADED`] line on, out of
/// the log's text (the rotated file's text first); empty if no process is in it.
pub fn last_app(text: &str) -> Vec<&str> {
    let lines: Vec<&str> = text.lines().collect();
    let start = lines
        .iter()
        .rposition(|l| parse_line(l).is_some_and(|p| p.text.starts_with(LOADED)));
    let Some(start) = start else {
        return Vec::new();
    };
    let pid = parse_line(lines[start]).map(|p| p.pid);
    lines[start..]
        .iter()
        .copied()
        .filter(|l| parse_line(l).map(|p| p.pid) == pid)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn timestamps_are_rfc3339_utc() {
        assert_eq!(rfc3339(UNIX_EPOCH), "1970-01-01T00:00:00.000Z");
        // 2000-02-29 is a leap day; 951782400 s after the epoch (date -ud 2000-02-29 +%s).
        let t = UNIX_EPOCH + Duration::from_millis(951_782_400_000 + 3_723_045);
        assert_eq!(rfc3339(t), "2000-02-29T01:02:03.045Z");
        // date -ud @1795374245 +%FT%TZ: 2026-11-22T19:04:05Z.
        let t = UNIX_EPOCH + Duration::from_secs(1_795_374_245);
        assert_eq!(rfc3339(t), "2026-11-22T19:04:05.000Z");
    }

    /// A pipe's two ends, the write end filled until it takes no more.
    fn full_pipe() -> (i32, i32) {
        let mut fds = [0; 2];
        // SAFETY: a valid array for the two descriptors.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        // SAFETY: fds[1] is ours; O_NONBLOCK only while it is filled.
        unsafe { libc::fcntl(fds[1], libc::F_SETFL, libc::O_NONBLOCK) };
        let block = [b'x'; 4096];
        // SAFETY: writes from a valid buffer to our own pipe.
        while unsafe { libc::write(fds[1], block.as_ptr().cast(), block.len()) } > 0 {}
        // SAFETY: as above: back to blocking, as an app's stderr is.
        unsafe { libc::fcntl(fds[1], libc::F_SETFL, 0) };
        (fds[0], fds[1])
    }

    #[test]
    fn a_full_pipe_takes_no_line_and_never_blocks() {
        let (read, write) = full_pipe();
        let t = std::time::Instant::now();
        assert!(!write_now(write, b"contrastxr: a line\n"));
        assert!(
            t.elapsed() < Duration::from_millis(100),
            "{:?}",
            t.elapsed()
        );
        let mut room = [0u8; 65536];
        // SAFETY: reads into a valid buffer from our own pipe.
        assert!(unsafe { libc::read(read, room.as_mut_ptr().cast(), room.len()) } > 0);
        assert!(write_now(write, b"contrastxr: a line\n"));
        // SAFETY: both ends are ours.
        unsafe { (libc::close(read), libc::close(write)) };
    }

    #[test]
    fn last_app_is_the_last_loaded_process() {
        let text = "\
2026-01-01T00:00:00.000Z [pid 7] layer loaded into /usr/bin/a
2026-01-01T00:00:00.001Z [pid 7] contrastxr 0.1.0 on, app \"a\"
2026-01-01T00:00:01.000Z [pid 9] layer loaded into /usr/bin/b
2026-01-01T00:00:01.001Z [pid 7] a's late line
2026-01-01T00:00:01.002Z [pid 9] contrastxr 0.1.0 on, app \"b\"
not a log line
2026-01-01T00:00:02.000Z [pid 9] processing frames (2 views per frame)
";
        let lines = last_app(text);
        assert_eq!(lines.len(), 3, "{lines:?}");
        assert!(lines[0].ends_with("layer loaded into /usr/bin/b"));
        assert!(lines[2].ends_with("processing frames (2 views per frame)"));
        assert!(last_app("no log lines\n").is_empty());
    }
}
