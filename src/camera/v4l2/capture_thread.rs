//! The capture thread: opens the device, streams memory-mapped buffers, converts each frame to
//! RGBA and publishes it; on loss or stall it marks the source down and reopens with backoff.
//! Readers only ever touch the mailbox in `Shared`, so nothing here can block them.

use super::choose::choose_mode;
use super::devices::{device_dir, modes, probe};
use crate::camera::convert::{to_rgba_into, PixelFormat};
use crate::camera::error::CameraError;
use crate::camera::log_sink::log;
use crate::camera::mailbox::{Frame, Shared, SourceStatus};
use crate::camera::pool::ImagePool;
use crate::camera::smoothing::Smoother;
use crate::camera::source::{CaptureConfig, SourceSpec};
use std::io;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::mpsc::sync_channel;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use v4l::buffer::{Flags as BufferFlags, Metadata, Type};
use v4l::io::traits::CaptureStream;
use v4l::prelude::MmapStream;
use v4l::video::capture::Parameters;
use v4l::video::Capture as _;
use v4l::{Device, FourCC, Fraction};

/// How long the first open may take before `Background::open` gives up on the device.
const FIRST_OPEN_TIMEOUT: Duration = Duration::from_secs(10);
/// The longest a poll waits, so that a stop request is noticed promptly.
const POLL_SLICE: Duration = Duration::from_millis(100);
const FIRST_BACKOFF: Duration = Duration::from_millis(100);
/// A camera nobody took a frame from for this long is closed by its own thread (its light goes
/// off, its controls are restored) also when the app makes no more frame calls (paused, idle);
/// it opens again at the next use.
const CLOSE_UNUSED: Duration = Duration::from_secs(2);
/// How often a closed, unused camera looks for a new use.
const REST_POLL: Duration = Duration::from_millis(50);

/// Why a stream ended without an error.
enum Ended {
    /// Asked to stop: the source is closing.
    Stopped,
    /// Nobody took a frame for [`CLOSE_UNUSED`].
    Unused,
}
/// Buffers in the driver's queue: enough to ride out a slow conversion, few enough for latency.
const BUFFER_COUNT: u32 = 4;

/// An open, configured device.
struct Session {
    device: Device,
    format: PixelFormat,
    width: u32,
    height: u32,
    stride: u32,
    description: String,
    /// The camera's controls as they were before the layer changed them, put back at close.
    saved: super::controls::Saved,
}

impl Drop for Session {
    fn drop(&mut self) {
        super::controls::restore(&self.device, std::mem::take(&mut self.saved));
    }
}

/// Starts capturing; returns once the device is open and configured (or failed to be).
pub(crate) fn spawn(
    spec: &SourceSpec,
    cfg: &CaptureConfig,
) -> Result<(Arc<Shared>, JoinHandle<()>, String), CameraError> {
    // v4l2:auto chooses here, once: reopens after a loss take the same camera.
    let target = match spec {
        SourceSpec::V4l2Device(path) => Some(path.clone()),
        _ => Some(super::auto::resolve(&device_dir(), cfg).ok_or_else(|| {
            CameraError::NoDevice(format!(
                "no V4L2 capture device found in {} with a usable mode (video* absent, not capture devices, \
                 or none offers YUYV, NV12, MJPG, RGB3, BGR3 or GREY)",
                device_dir().display()
            ))
        })?),
    };
    let shared = Arc::new(Shared::new());
    let (tx, rx) = sync_channel(1);
    let (thread_shared, cfg) = (shared.clone(), cfg.clone());
    let thread = std::thread::Builder::new()
        .name("contrastxr-camera".into())
        .spawn(move || {
            crate::camera::priority::yield_to_the_app();
            match open_session(target.as_ref(), &cfg) {
                Ok(session) => {
                    let _ = tx.send(Ok(session.description.clone()));
                    run(target, &cfg, &thread_shared, Some(session));
                }
                // Busy now, perhaps free in a moment: the source opens, and the thread retries
                // with growing waits (frames pass through meanwhile).
                Err(CameraError::Busy(e)) => {
                    let _ = tx.send(Ok(format!("{e}, retrying")));
                    run(target, &cfg, &thread_shared, None);
                }
                Err(e) => {
                    let _ = tx.send(Err(e));
                }
            }
        })
        .map_err(|e| CameraError::Device(format!("cannot start the capture thread: {e}")))?;
    match rx.recv_timeout(FIRST_OPEN_TIMEOUT) {
        Ok(Ok(description)) => Ok((shared, thread, description)),
        Ok(Err(e)) => {
            let _ = thread.join();
            Err(e)
        }
        Err(_) => {
            shared
                .stop
                .store(true, std::sync::atomic::Ordering::Release);
            Err(CameraError::Device(
                "the camera did not answer within 10 s".into(),
            ))
        }
    }
}

fn open_session(target: Option<&PathBuf>, cfg: &CaptureConfig) -> Result<Session, CameraError> {
    let path = target.cloned().unwrap_or_else(device_dir);
    let shown = path.display();
    let (device, info) = probe(&path).map_err(|e| match e.kind() {
        io::ErrorKind::NotFound => CameraError::NoDevice(format!("{shown} does not exist")),
        _ => CameraError::Device(format!("cannot open {shown}: {e}")),
    })?;
    if !info.capture {
        return Err(CameraError::NoDevice(format!(
            "{shown} is not a video capture device"
        )));
    }
    let all = modes(&device).map_err(|e| CameraError::Device(format!("{shown}: {e}")))?;
    let mode = choose_mode(&all, cfg.width, cfg.height, cfg.fps).ok_or_else(|| {
        CameraError::Unsupported(format!(
            "{shown} offers none of YUYV, NV12, MJPG, RGB3, BGR3, GREY"
        ))
    })?;
    let device_err = |e: io::Error| match e.raw_os_error() {
        Some(libc::EBUSY) => CameraError::Busy(format!(
            "{shown} is busy (another program is capturing from it)"
        )),
        _ => CameraError::Device(format!("{shown}: {e}")),
    };
    let mut wanted = device.format().map_err(device_err)?;
    (wanted.width, wanted.height, wanted.fourcc) =
        (mode.width, mode.height, FourCC::new(&mode.fourcc));
    let got = device.set_format(&wanted).map_err(device_err)?;
    let format = PixelFormat::from_fourcc(got.fourcc.repr).ok_or_else(|| {
        CameraError::Unsupported(format!(
            "{shown} switched to unsupported format {}",
            got.fourcc
        ))
    })?;
    let saved = super::controls::apply(&device, &cfg.controls, &shown.to_string());
    if mode.interval.0 > 0 {
        let rate = Parameters::new(Fraction::new(mode.interval.0, mode.interval.1));
        if let Err(e) = device.set_params(&rate) {
            log(&format!(
                "{shown}: cannot set the frame rate, using the driver's: {e}"
            ));
        }
    }
    let fps = device.params().map(|p| p.interval).map_or(0.0, |f| {
        if f.numerator > 0 {
            f64::from(f.denominator) / f64::from(f.numerator)
        } else {
            0.0
        }
    });
    let description = format!(
        "{shown} ({}) {}x{} {} at {fps:.0} fps",
        info.card, got.width, got.height, got.fourcc
    );
    Ok(Session {
        device,
        format,
        width: got.width,
        height: got.height,
        stride: got.stride,
        description,
        saved,
    })
}

/// The thread's life: stream, and after each loss reopen with doubling waits, until stopped.
fn run(target: Option<PathBuf>, cfg: &CaptureConfig, shared: &Shared, first: Option<Session>) {
    let mut capture = Capture {
        sequence: 0,
        smoother: cfg.smoothing.map(Smoother::new),
        status: StatusLog::default(),
        pool: ImagePool::default(),
        exposure_us: cfg.controls.exposure_us,
    };
    if let Some(first) = &first {
        log(&format!("opened {}", first.description));
    }
    let mut session = first;
    let mut backoff = FIRST_BACKOFF;
    let mut open_error = None;
    // A device that opens but delivers nothing is reopened quietly, with growing waits.
    let mut quiet = false;
    while !shared.stopping() {
        let current = match session.take() {
            Some(s) => s,
            None => match open_session(target.as_ref(), cfg) {
                Ok(s) => {
                    if !quiet {
                        log(&format!("reopened {}", s.description));
                    }
                    open_error = None;
                    s
                }
                Err(e) => {
                    let message = e.to_string();
                    if open_error.as_ref() != Some(&message) {
                        log(&format!("cannot open yet: {message}"));
                        open_error = Some(message);
                    }
                    capture.status.update(shared, cfg);
                    shared.sleep_until(Instant::now() + backoff);
                    backoff = (backoff * 2).min(cfg.max_backoff.max(FIRST_BACKOFF));
                    continue;
                }
            },
        };
        // The v4l crate panics in Drop on some driver errors; that is one more way to lose
        // the device, not a reason to take the application down.
        let sequence_before = capture.sequence;
        let ended = catch_unwind(AssertUnwindSafe(|| capture.stream(&current, cfg, shared)));
        drop(current);
        let delivered = capture.sequence > sequence_before;
        match ended {
            Ok(Ok(Ended::Stopped)) => break,
            Ok(Ok(Ended::Unused)) => {
                rest_until_used(shared);
                backoff = FIRST_BACKOFF;
                continue;
            }
            _ if quiet && !delivered => {}
            Ok(Err(e)) => log(&format!("lost the camera: {e}")),
            Err(_) => log("lost the camera: the driver failed (v4l panicked)"),
        }
        quiet = !delivered;
        if delivered {
            backoff = FIRST_BACKOFF;
        } else {
            shared.sleep_until(Instant::now() + backoff);
            backoff = (backoff * 2).min(cfg.max_backoff.max(FIRST_BACKOFF));
        }
        shared.mark_down();
        capture.status.update(shared, cfg);
    }
}

/// After the device was closed for want of use: says so, and waits (without the device) until
/// a frame is taken again or the source stops.
fn rest_until_used(shared: &Shared) {
    log("no frame taken for 2 s: the camera is closed until the next one");
    shared.rest();
    let rested = Instant::now();
    while !shared.stopping() && !shared.used_since(rested) {
        shared.sleep_until(Instant::now() + REST_POLL);
    }
}

struct Capture {
    /// Sequence of the last published frame; continues across reopens.
    sequence: u64,
    smoother: Option<Smoother>,
    status: StatusLog,
    /// The converted frames, reused (see `pool`).
    pool: ImagePool,
    /// A fixed exposure time: a start-of-exposure timestamp then moves to mid-exposure.
    exposure_us: Option<u32>,
}

impl Capture {
    /// Streams until stopped (`Ok`) or until the device fails or stalls (`Err`).
    fn stream(
        &mut self,
        session: &Session,
        cfg: &CaptureConfig,
        shared: &Shared,
    ) -> io::Result<Ended> {
        let mut stream =
            MmapStream::with_buffers(&session.device, Type::VideoCapture, BUFFER_COUNT)?;
        // `next()` must never time out once streaming: the v4l crate would then queue the same
        // buffer twice on the following call (vb2 refuses that with EINVAL). So the waiting
        // is done by our own short polls, and `next()` runs only when a buffer is ready. The
        // first `next()` starts the stream and may wait up to the stall timeout.
        stream.set_timeout(cfg.stall_timeout);
        let handle = session.device.handle();
        let slice = POLL_SLICE.min(cfg.stall_timeout).as_millis() as i32;
        let mut last_frame = Instant::now();
        let mut started = false;
        let mut bad_frame_logged = false;
        let opened = Instant::now();
        while !shared.stopping() {
            self.status.update(shared, cfg);
            if shared.unused_for(opened) > CLOSE_UNUSED {
                return Ok(Ended::Unused);
            }
            let stalled = || {
                let ms = cfg.stall_timeout.as_millis();
                io::Error::new(io::ErrorKind::TimedOut, format!("no frame for {ms} ms"))
            };
            if last_frame.elapsed() > cfg.stall_timeout {
                return Err(stalled());
            }
            if started && handle.poll(libc::POLLIN, slice)? == 0 {
                continue;
            }
            started = true;
            let (data, meta) = CaptureStream::next(&mut stream).map_err(|e| match e.kind() {
                io::ErrorKind::TimedOut => stalled(),
                _ => e,
            })?;
            // A newer buffer is already filled: this one is stale. Only the newest frame is
            // converted and handed over, so no queue of old driver buffers lies between the
            // camera and the frame (the next `next()` gives this buffer back to the driver).
            if handle.poll(libc::POLLIN, 0)? > 0 {
                last_frame = Instant::now();
                continue;
            }
            match self.convert(session, data, meta) {
                Ok(frame) => {
                    shared.publish(frame);
                    last_frame = Instant::now();
                }
                Err(e) if !bad_frame_logged => {
                    log(&format!("skipping bad frames: {e}"));
                    bad_frame_logged = true;
                }
                Err(_) => {}
            }
        }
        Ok(Ended::Stopped)
    }

    fn convert(
        &mut self,
        session: &Session,
        data: &[u8],
        meta: &Metadata,
    ) -> Result<Frame, String> {
        if meta.flags.contains(BufferFlags::ERROR) {
            return Err("the driver marked a frame as corrupt".into());
        }
        let used = match meta.bytesused as usize {
            0 => data.len(),
            n => n.min(data.len()),
        };
        let size = (session.width, session.height, session.stride);
        let image = to_rgba_into(session.format, &data[..used], size, self.pool.take())?;
        let image = match self.smoother.as_mut() {
            Some(s) => s.apply(image),
            None => image,
        };
        self.sequence += 1;
        // time_t is 32 bits on some targets.
        #[allow(clippy::unnecessary_cast)]
        let stamped = instant_of(meta.timestamp.sec as i64, meta.timestamp.usec as i64);
        let captured_at = capture_time(meta.flags, stamped, self.exposure_us);
        Ok(Frame {
            image: self.pool.share(image),
            sequence: self.sequence,
            captured_at: Some(captured_at),
            prepared: None,
        })
    }
}

/// When a frame was captured: the driver's timestamp when it says the clock is monotonic (at
/// mid-exposure when it stamps the start of exposure and the exposure time is fixed), else the
/// time it was dequeued.
fn capture_time(flags: BufferFlags, stamped: Instant, exposure_us: Option<u32>) -> Instant {
    let clock = flags & BufferFlags::TIMESTAMP_MASK;
    if clock != BufferFlags::TIMESTAMP_MONOTONIC {
        return Instant::now();
    }
    let start_of_exposure = flags & BufferFlags::TSTAMP_SRC_MASK == BufferFlags::TSTAMP_SRC_SOE;
    match exposure_us {
        Some(us) if start_of_exposure => stamped + Duration::from_micros(u64::from(us) / 2),
        _ => stamped,
    }
}

/// Maps a driver timestamp (CLOCK_MONOTONIC, as UVC and vb2 drivers stamp buffers) to an
/// `Instant`; an implausible one (another clock, or none) becomes "now".
fn instant_of(sec: i64, usec: i64) -> Instant {
    let now = Instant::now();
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec and CLOCK_MONOTONIC always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    #[allow(clippy::unnecessary_cast)] // time_t and c_long are 32 bits on some targets
    let now_us = ts.tv_sec as i64 * 1_000_000 + ts.tv_nsec as i64 / 1000;
    let age_us = now_us - (sec * 1_000_000 + usec);
    if (0..10_000_000).contains(&age_us) {
        now.checked_sub(Duration::from_micros(age_us as u64))
            .unwrap_or(now)
    } else {
        now
    }
}

/// Logs each change of status once.
#[derive(Default)]
struct StatusLog {
    last: Option<std::mem::Discriminant<SourceStatus>>,
}

impl StatusLog {
    fn update(&mut self, shared: &Shared, cfg: &CaptureConfig) {
        let status = shared.status(Instant::now(), cfg.stall_timeout, cfg.grace);
        let kind = std::mem::discriminant(&status);
        if self.last == Some(kind) {
            return;
        }
        self.last = Some(kind);
        let grace = cfg.grace.as_millis();
        log(match status {
            SourceStatus::Waiting { .. } => "waiting for the first frame",
            SourceStatus::Live => "live",
            SourceStatus::Stale { .. } => "no new frames, keeping the last one",
            SourceStatus::Lost if grace == 0 => "lost, passing frames through",
            SourceStatus::Lost => "lost for longer than the grace period, passing frames through",
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capture_time_follows_the_drivers_clock_flags() {
        let stamped = Instant::now() - Duration::from_millis(40);
        let mono = BufferFlags::TIMESTAMP_MONOTONIC;
        assert_eq!(capture_time(mono, stamped, Some(10_000)), stamped);
        let soe = mono | BufferFlags::TSTAMP_SRC_SOE;
        assert_eq!(
            capture_time(soe, stamped, Some(10_000)),
            stamped + Duration::from_millis(5)
        );
        assert_eq!(capture_time(soe, stamped, None), stamped);
        // Another clock: the dequeue time.
        let copied = capture_time(BufferFlags::TIMESTAMP_COPY, stamped, None);
        assert!(copied.duration_since(stamped) >= Duration::from_millis(40));
    }
}
