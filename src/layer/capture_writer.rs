//! The capture thread (`contrastxr-capture`): captured views get their perception report and
//! are written here, off the app's thread, in the order they were taken; the out-of-reach
//! check's read-backs get their report and no files. The app's thread only hands over what it read back
//! (`capture_files::CaptureJob`), never waiting for a file system: a capture folder on a hung
//! mount, a FIFO or a slow disk delays the files, not the frames. What waits to be written is
//! bounded ([`MOST_WAITING`]): past it a view's capture is dropped, said once.
//! `xrDestroyInstance` and the process's exit wait (boundedly) for what was handed over.

use super::capture_files::CaptureJob;
use super::capture_report::{report_step, view_report};
use super::ffi::contain;
use super::log;
use super::reach_advice;
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::{Condvar, Mutex, MutexGuard, Once, OnceLock};
use std::time::{Duration, Instant};

/// The most bytes of captured pixels waiting to be written.
pub const MOST_WAITING: usize = 256 << 20;

/// The longest `xrDestroyInstance` waits for the captures handed over before it.
pub const INSTANCE_WAIT: Duration = Duration::from_millis(300);

/// The longest the process's exit waits for them.
pub const EXIT_WAIT: Duration = Duration::from_secs(5);

/// The capture thread ends after this long without a capture to write.
const IDLE_END: Duration = Duration::from_secs(1);

#[derive(Default)]
struct Waiting {
    jobs: usize,
    bytes: usize,
}

struct Writer {
    jobs: Mutex<Option<Sender<CaptureJob>>>,
    waiting: Mutex<Waiting>,
    written: Condvar,
}

fn writer() -> &'static Writer {
    static WRITER: OnceLock<Writer> = OnceLock::new();
    WRITER.get_or_init(|| Writer {
        jobs: Mutex::new(None),
        waiting: Mutex::new(Waiting::default()),
        written: Condvar::new(),
    })
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // Plain counters and a sender: a panic while holding the lock leaves them usable.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Hands a captured view to the capture thread (started at the first), without waiting.
pub fn write(job: CaptureJob) {
    let w = writer();
    let bytes = job.bytes();
    {
        let mut waiting = lock(&w.waiting);
        if waiting.bytes + bytes > MOST_WAITING && waiting.jobs > 0 {
            drop(waiting);
            log::once(
                "capture-behind",
                &format!(
                    "capture of {} dropped: {} of captures wait to be written (the capture \
                     folder's file system is slow or stalled)",
                    job.stem,
                    crate::user_file::size_text(MOST_WAITING as u64)
                ),
            );
            return;
        }
        waiting.jobs += 1;
        waiting.bytes += bytes;
    }
    let mut jobs = lock(&w.jobs);
    if jobs.is_none() {
        *jobs = start();
    }
    let sent = jobs.as_ref().is_some_and(|tx| tx.send(job).is_ok());
    if !sent {
        *jobs = None;
        done(bytes);
        log::once("capture-thread", "capture failed: no capture thread");
    }
}

/// Starts the capture thread; None (said once) when the system gives no thread.
fn start() -> Option<Sender<CaptureJob>> {
    let (tx, rx) = channel::<CaptureJob>();
    let spawned = std::thread::Builder::new()
        .name("contrastxr-capture".into())
        .spawn(move || {
            while let Some(job) = next_job(&rx) {
                let bytes = job.bytes();
                let written = contain("while writing", || report_and_write(job))
                    .unwrap_or_else(|panic| Err(panic.to_string()));
                if let Err(e) = written {
                    log::once("capture-failed", &format!("capture failed: {e}"));
                }
                done(bytes);
            }
        });
    match spawned {
        Ok(_) => {
            static AT_EXIT: Once = Once::new();
            // SAFETY: at_exit is a plain function of this library, which is never unmapped
            // (RTLD_NODELETE); glibc's atexit runs it at the process's exit.
            AT_EXIT.call_once(|| unsafe {
                libc::atexit(at_exit);
            });
            Some(tx)
        }
        Err(e) => {
            log::once(
                "capture-thread",
                &format!("capture failed: no capture thread ({e})"),
            );
            None
        }
    }
}

/// A view's perception report (over a bounded sample of a large view), the out-of-reach
/// advice, then its files, if it has any.
fn report_and_write(mut job: CaptureJob) -> Result<(), String> {
    let step = report_step(job.extent.0, job.extent.1);
    let report = view_report(&job, step);
    reach_advice::consider(&report, &job.view.params);
    if let (Some(json), Ok(serde_json::Value::Object(keys))) =
        (job.json.as_object_mut(), serde_json::to_value(&report))
    {
        json.extend(keys);
        json.insert("perception_step".into(), step.into());
    }
    job.write()
}

/// The next capture to write; None once none has come for [`IDLE_END`], when the thread ends
/// (the next capture starts another), so that no thread of the layer outlives its use.
fn next_job(rx: &Receiver<CaptureJob>) -> Option<CaptureJob> {
    match rx.recv_timeout(IDLE_END) {
        Ok(job) => Some(job),
        Err(RecvTimeoutError::Disconnected) => None,
        Err(RecvTimeoutError::Timeout) => {
            // Under the senders' lock no capture can be handed over meanwhile.
            let mut jobs = lock(&writer().jobs);
            if let Ok(job) = rx.try_recv() {
                return Some(job);
            }
            *jobs = None;
            None
        }
    }
}

/// One job written (or failed): counted off, and anyone waiting told.
fn done(bytes: usize) {
    let w = writer();
    let mut waiting = lock(&w.waiting);
    waiting.jobs = waiting.jobs.saturating_sub(1);
    waiting.bytes = waiting.bytes.saturating_sub(bytes);
    w.written.notify_all();
}

/// Waits until every capture handed over so far is written, at most `limit`. True when none
/// waits any more.
pub fn finish(limit: Duration) -> bool {
    let w = writer();
    let deadline = Instant::now() + limit;
    let mut waiting = lock(&w.waiting);
    while waiting.jobs > 0 {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return false;
        }
        waiting = w
            .written
            .wait_timeout(waiting, left)
            .unwrap_or_else(|p| p.into_inner())
            .0;
    }
    true
}

extern "C" fn at_exit() {
    // A panic must not unwind into libc.
    let _ = contain("at exit", || {
        if !finish(EXIT_WAIT) {
            log::info("exiting with captures not yet written (the capture folder's file system is stalled)");
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::Params;
    use crate::gpu::{PixelFormat, PixelLayout};
    use crate::image::RgbaImage;
    use crate::layer::capture_files::ReportView;
    use std::sync::Arc;

    fn capture_threads() -> usize {
        std::fs::read_dir("/proc/self/task")
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|t| std::fs::read_to_string(t.path().join("comm")).ok())
            .filter(|n| n.trim().starts_with("contrastxr-capt"))
            .count()
    }

    /// A capture handed over is written off the caller's thread, `finish` waits for it, and the
    /// capture thread ends on its own once idle.
    #[test]
    fn captures_are_written_by_a_thread_that_ends_when_idle() {
        let scratch = crate::scratch::ScratchDir::new("writer");
        // A folder the writer makes.
        let dir = scratch.join("captures");
        write(CaptureJob {
            dir: Some(dir.clone()),
            stem: "frame-0-view-0".into(),
            format: PixelFormat {
                layout: PixelLayout::Rgba8,
                srgb: true,
            },
            extent: (1, 1),
            display: vec![1, 2, 3, 255],
            output: vec![4, 5, 6, 255],
            background: Arc::new(RgbaImage::new(1, 1, [7, 8, 9, 255])),
            json: serde_json::json!({"frame": 0}),
            view: ReportView {
                params: Params::default(),
                mapping: Params::default().camera_mapping(),
                pixels_per_degree: 20.0,
            },
        });
        assert!(finish(Duration::from_secs(5)));
        assert!(dir.join("frame-0-view-0.json").is_file());
        assert_eq!(capture_threads(), 1);
        std::thread::sleep(IDLE_END + Duration::from_millis(500));
        assert_eq!(capture_threads(), 0, "the capture thread outlived its use");
    }
}
