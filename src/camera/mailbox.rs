//! Frames, source status, and the latest-frame mailbox shared with the producer thread.

use crate::gpu::core::blurred_texels::{BlurTaps, BlurredTexels, TexelSink};
use crate::image::RgbaImage;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, TryLockError};
use std::time::{Duration, Instant};

/// One background frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// 8-bit sRGB RGBA, top row first.
    pub image: Arc<RgbaImage>,
    /// Starts at 1 and grows with each new frame (it may skip), so a consumer preprocesses once
    /// per new value. Static sources keep the same value for ever.
    pub sequence: u64,
    /// When the frame was captured (for V4L2, the driver's timestamp mapped to `Instant`); None
    /// for a still image (`image:`, `color:`), which is no capture of any moment and so stays
    /// head-fixed.
    pub captured_at: Option<Instant>,
    /// The frame decoded and blurred with the blur the consumer asked for (`Shared::want`),
    /// made on the producer's thread before the frame is published; None when none was asked.
    pub prepared: Option<Arc<BlurredTexels>>,
}

/// Health of a source, for the consumer's grace-period logic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceStatus {
    /// Opened, no frame yet.
    Waiting { since: Instant },
    /// Frames are arriving.
    Live,
    /// The device stalled or vanished; the last good frame is still served.
    Stale { since: Instant },
    /// Past the grace period: `latest()` returns `None`, the consumer passes frames through.
    Lost,
}

/// Shared between a producer thread and the readers. Readers never block: the mailbox lock is
/// only ever held for an `Arc` clone or swap, and readers use `try_lock`.
pub(crate) struct Shared {
    mailbox: Mutex<Option<Frame>>,
    epoch: Instant,
    /// Nanoseconds after `epoch` (+1; 0 = never) of the newest frame.
    last_frame_ns: AtomicU64,
    /// Nanoseconds after `epoch` (+1; 0 = not down) since the device has been lost.
    down_since_ns: AtomicU64,
    pub(crate) stop: AtomicBool,
    /// Nanoseconds after `epoch` (+1; 0 = never) the consumer last took a frame.
    last_used_ns: AtomicU64,
    /// Nanoseconds after `epoch` (+1; 0 = not resting) since the producer closed its device
    /// because nobody took a frame (it opens again at the next use).
    resting_since_ns: AtomicU64,
    /// The blur each published frame is prepared with (None: not prepared).
    blur: Mutex<Option<BlurTaps>>,
    /// Where prepared texels are written before the frame is published (None: nowhere).
    sink: Mutex<Option<Arc<dyn TexelSink>>>,
}

impl Shared {
    pub(crate) fn new() -> Self {
        Shared {
            mailbox: Mutex::new(None),
            epoch: Instant::now(),
            last_frame_ns: AtomicU64::new(0),
            down_since_ns: AtomicU64::new(0),
            stop: AtomicBool::new(false),
            last_used_ns: AtomicU64::new(0),
            resting_since_ns: AtomicU64::new(0),
            blur: Mutex::new(None),
            sink: Mutex::new(None),
        }
    }

    fn stamp(&self, t: Instant) -> u64 {
        t.saturating_duration_since(self.epoch).as_nanos() as u64 + 1
    }

    fn instant(&self, stamp: u64) -> Instant {
        self.epoch + Duration::from_nanos(stamp - 1)
    }

    /// Publishes `frame`, first prepared with the blur asked for and handed to the sink: on the
    /// producer's thread, so that the consumer's frame calls at most copy it.
    pub(crate) fn publish(&self, mut frame: Frame) {
        let blur = *self.blur.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(blur) = blur {
            let texels = BlurredTexels::prepare(&frame.image, blur);
            // Cloned out of the lock: the consumer's `deliver_to` never waits for a write.
            let sink = self.sink.lock().unwrap_or_else(|e| e.into_inner()).clone();
            if let Some(sink) = sink {
                sink.offer(&texels);
            }
            frame.prepared = Some(Arc::new(texels));
        }
        let mut slot = self.mailbox.lock().unwrap_or_else(|e| e.into_inner());
        *slot = Some(frame);
        drop(slot);
        self.last_frame_ns
            .store(self.stamp(Instant::now()), Ordering::Release);
        self.down_since_ns.store(0, Ordering::Release);
        self.resting_since_ns.store(0, Ordering::Release);
    }

    /// Notes that the consumer took a frame now (it still wants the source).
    pub(crate) fn mark_used(&self) {
        self.last_used_ns
            .store(self.stamp(Instant::now()), Ordering::Release);
    }

    /// How long nobody has taken a frame, counted from `opened` at the latest.
    pub(crate) fn unused_for(&self, opened: Instant) -> Duration {
        let used = self.last_used_ns.load(Ordering::Acquire);
        let since = match used {
            0 => opened,
            u => self.instant(u).max(opened),
        };
        since.elapsed()
    }

    /// Whether the consumer took a frame after `t`.
    pub(crate) fn used_since(&self, t: Instant) -> bool {
        let used = self.last_used_ns.load(Ordering::Acquire);
        used != 0 && self.instant(used) > t
    }

    /// The producer closed its device for want of use: until its next frame the consumer sees
    /// it waiting (from its next use), not lost.
    pub(crate) fn rest(&self) {
        self.resting_since_ns
            .store(self.stamp(Instant::now()), Ordering::Release);
    }

    /// Asks for the frames published from now on to be prepared with `blur`. Never waits: while
    /// the producer reads the setting, the request is left to the next call.
    pub(crate) fn want(&self, blur: BlurTaps) {
        if let Ok(mut slot) = self.blur.try_lock() {
            *slot = Some(blur);
        }
    }

    /// Makes `sink` (None: none) receive the prepared texels of the frames published from now
    /// on. Never waits: while the producer reads the setting, the request is left to the next
    /// call.
    pub(crate) fn deliver_to(&self, sink: Option<Arc<dyn TexelSink>>) {
        if let Ok(mut slot) = self.sink.try_lock() {
            let same = match (&*slot, &sink) {
                (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                (a, b) => a.is_none() && b.is_none(),
            };
            if !same {
                *slot = sink;
            }
        }
    }

    pub(crate) fn stopping(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// Sleeps until `deadline` or until asked to stop (`Drop` unparks the thread).
    pub(crate) fn sleep_until(&self, deadline: Instant) {
        while !self.stopping() {
            let now = Instant::now();
            if now >= deadline {
                return;
            }
            std::thread::park_timeout(deadline - now);
        }
    }

    pub(crate) fn mark_down(&self) {
        let stamp = self.stamp(Instant::now());
        let _ = self
            .down_since_ns
            .compare_exchange(0, stamp, Ordering::AcqRel, Ordering::Acquire);
    }

    /// The newest frame without waiting. Contention lasts nanoseconds (an `Arc` clone), so a
    /// few spins settle it; if they do not, the reader gets `None` rather than waiting.
    pub(crate) fn peek(&self) -> Option<Frame> {
        for _ in 0..1000 {
            match self.mailbox.try_lock() {
                Ok(slot) => return slot.clone(),
                Err(TryLockError::Poisoned(e)) => return e.into_inner().clone(),
                Err(TryLockError::WouldBlock) => std::hint::spin_loop(),
            }
        }
        None
    }

    /// Status at `now` from the two timestamps: no thread has to be scheduled for a stall to
    /// show, so a blocked capture thread still reads as `Stale`, then `Lost`.
    pub(crate) fn status(&self, now: Instant, stall: Duration, grace: Duration) -> SourceStatus {
        let last = self.last_frame_ns.load(Ordering::Acquire);
        let down = self.down_since_ns.load(Ordering::Acquire);
        let resting = self.resting_since_ns.load(Ordering::Acquire);
        if resting != 0 {
            // Reopening since the first use after the rest: as long as an open may take.
            let used = self.last_used_ns.load(Ordering::Acquire).max(resting);
            let since = self.instant(used);
            return if now.saturating_duration_since(since) > stall + grace {
                SourceStatus::Lost
            } else {
                SourceStatus::Waiting { since }
            };
        }
        if last == 0 {
            // `epoch` is when the source was opened: waiting (or reopening) since then.
            let since = self.epoch;
            return if now.saturating_duration_since(since) > stall + grace {
                SourceStatus::Lost
            } else {
                SourceStatus::Waiting { since }
            };
        }
        let stalled_at = self.instant(last) + stall;
        let since = match down {
            0 if now <= stalled_at => return SourceStatus::Live,
            0 => stalled_at,
            d => self.instant(d).min(stalled_at),
        };
        if now.saturating_duration_since(since) > grace {
            SourceStatus::Lost
        } else {
            SourceStatus::Stale { since }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> Frame {
        Frame {
            image: Arc::new(RgbaImage::new(1, 1, [1, 2, 3, 255])),
            sequence: 1,
            captured_at: Some(Instant::now()),
            prepared: None,
        }
    }

    #[test]
    fn status_follows_the_timeline() {
        let s = Shared::new();
        let (stall, grace) = (Duration::from_millis(100), Duration::from_millis(200));
        let t0 = Instant::now();
        assert!(matches!(
            s.status(t0, stall, grace),
            SourceStatus::Waiting { .. }
        ));
        assert_eq!(
            s.status(t0 + Duration::from_secs(1), stall, grace),
            SourceStatus::Lost
        );
        s.publish(frame());
        let t1 = Instant::now();
        assert_eq!(s.status(t1, stall, grace), SourceStatus::Live);
        let stalled = s.status(t1 + Duration::from_millis(150), stall, grace);
        assert!(matches!(stalled, SourceStatus::Stale { .. }), "{stalled:?}");
        assert_eq!(
            s.status(t1 + Duration::from_millis(400), stall, grace),
            SourceStatus::Lost
        );
        s.mark_down();
        assert!(matches!(
            s.status(Instant::now(), stall, grace),
            SourceStatus::Stale { .. }
        ));
        s.publish(frame());
        assert_eq!(s.status(Instant::now(), stall, grace), SourceStatus::Live);
    }

    #[test]
    fn peek_returns_the_newest_frame() {
        let s = Shared::new();
        assert!(s.peek().is_none());
        let mut f = frame();
        s.publish(f.clone());
        f.sequence = 2;
        s.publish(f);
        assert_eq!(s.peek().map(|f| f.sequence), Some(2));
    }

    #[test]
    fn a_resting_source_waits_from_its_next_use_and_lives_again_at_its_next_frame() {
        let s = Shared::new();
        let (stall, grace) = (Duration::from_millis(100), Duration::from_millis(200));
        s.publish(frame());
        s.rest();
        let rested = Instant::now();
        assert!(!s.used_since(rested));
        // Long after the last frame, a resting source is not lost: it waits.
        let later = rested + Duration::from_millis(250);
        assert!(matches!(
            s.status(later, stall, grace),
            SourceStatus::Waiting { .. }
        ));
        std::thread::sleep(Duration::from_millis(2));
        s.mark_used();
        assert!(s.used_since(rested));
        // From its next use it has an open's time to deliver, then it is lost.
        let much_later = Instant::now() + stall + grace + Duration::from_millis(50);
        assert_eq!(s.status(much_later, stall, grace), SourceStatus::Lost);
        s.publish(frame());
        assert_eq!(s.status(Instant::now(), stall, grace), SourceStatus::Live);
    }
}
