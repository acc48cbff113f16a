//! The GPU time of the layer's work per enhanced frame, as the session's engine measures it on
//! the app's queue or context (timestamps from when the app's earlier work has finished to
//! when the layer's has), said in the log: once a minute for the minute past, and for the whole
//! session when it ends. A frame's CPU time inside xrEndFrame says nothing of this on a GPU,
//! where the work runs after the call returns. Bounded however long the session: histograms,
//! not a list of frames.

use super::log::GPU_TIME;
use std::time::{Duration, Instant};

/// How often the log says the last period's figures.
const PERIOD: Duration = Duration::from_secs(60);

/// The histogram's bins: the first holds times under FIRST, each next one a RATIO wider; the
/// last also holds everything beyond. A quantile is read within half a bin (0.5 %).
const FIRST: f64 = 1e-6;
const RATIO: f64 = 1.01;
/// 1 us * 1.01^1620 ~ 10 s.
const BINS: usize = 1620;

/// Frame GPU times, binned on a log scale.
#[derive(Clone)]
struct Histogram {
    bins: Vec<u32>,
    count: u64,
    largest: Duration,
}

impl Histogram {
    fn new() -> Histogram {
        Histogram {
            bins: vec![0; BINS],
            count: 0,
            largest: Duration::ZERO,
        }
    }

    fn bin(t: Duration) -> usize {
        let s = t.as_secs_f64();
        if s < FIRST {
            return 0;
        }
        ((s / FIRST).ln() / RATIO.ln())
            .floor()
            .min((BINS - 1) as f64) as usize
            + 1
    }

    fn add(&mut self, t: Duration) {
        let bin = Self::bin(t).min(BINS - 1);
        self.bins[bin] = self.bins[bin].saturating_add(1);
        self.count += 1;
        self.largest = self.largest.max(t);
    }

    /// The time below which a fraction `q` of the frames fall: the geometric middle of its
    /// bin, never above the largest time seen.
    fn quantile(&self, q: f64) -> Duration {
        let rank = ((q * self.count as f64).ceil() as u64).clamp(1, self.count.max(1));
        let mut seen = 0u64;
        for (k, &n) in self.bins.iter().enumerate() {
            seen += u64::from(n);
            if seen >= rank {
                let middle = match k {
                    0 => FIRST / 2.0,
                    k => FIRST * RATIO.powf(k as f64 - 0.5),
                };
                return Duration::from_secs_f64(middle).min(self.largest);
            }
        }
        self.largest
    }

    /// "median 0.412 ms, 95th percentile 0.530 ms, largest 1.203 ms, 1200 frames".
    fn summary(&self) -> String {
        let ms = |t: Duration| t.as_secs_f64() * 1e3;
        format!(
            "median {:.3} ms, 95th percentile {:.3} ms, largest {:.3} ms, {} frame{}",
            ms(self.quantile(0.5)),
            ms(self.quantile(0.95)),
            ms(self.largest),
            self.count,
            if self.count == 1 { "" } else { "s" }
        )
    }
}

/// A session's frame GPU times: the current period's and the whole session's; and the app's
/// frame period, from the display times of its xrEndFrame calls, to hold them against.
pub struct GpuTimeLog {
    period: Histogram,
    session: Histogram,
    /// Steps between successive frames' display times over the session.
    frame_period: Histogram,
    last_display_time: Option<i64>,
    /// When the current period began (the first measured frame's arrival, then each line).
    since: Option<Instant>,
}

impl Default for GpuTimeLog {
    fn default() -> Self {
        GpuTimeLog {
            period: Histogram::new(),
            session: Histogram::new(),
            frame_period: Histogram::new(),
            last_display_time: None,
            since: None,
        }
    }
}

impl GpuTimeLog {
    /// Takes a frame's display time (xrEndFrame's `displayTime`, ns): the step from the last
    /// one is a frame period (a frame the app skipped makes one step of two periods: the
    /// median stays the period). Steps not in (0, 1 s] (a paused app, a clock gone back) are
    /// not counted.
    pub fn display_time(&mut self, ns: i64) {
        let last = self.last_display_time.replace(ns);
        let step = last.map_or(0, |last| ns.saturating_sub(last));
        if step > 0 && step <= 1_000_000_000 {
            self.frame_period.add(Duration::from_nanos(step as u64));
        }
    }

    /// ` (frame period 11.1 ms)`, once display times came; empty before.
    fn period_words(&self) -> String {
        match self.frame_period.count {
            0 => String::new(),
            _ => format!(
                " (frame period {:.1} ms)",
                self.frame_period.quantile(0.5).as_secs_f64() * 1e3
            ),
        }
    }

    /// Takes frames' measured GPU times; returns the log's line for the period once a period
    /// has passed since the last (or since the first measured frame).
    pub fn add(&mut self, times: &[Duration], now: Instant) -> Option<String> {
        if times.is_empty() {
            return None;
        }
        for &t in times {
            self.period.add(t);
            self.session.add(t);
        }
        let since = *self.since.get_or_insert(now);
        if now.duration_since(since) < PERIOD {
            return None;
        }
        let line = format!(
            "{GPU_TIME}the last {} s: {}{}",
            now.duration_since(since).as_secs(),
            self.period.summary(),
            self.period_words()
        );
        self.period = Histogram::new();
        self.since = Some(now);
        Some(line)
    }

    /// The log's line for the whole session (None where no frame was measured: the device
    /// or context has no timestamps, or nothing was enhanced).
    pub fn session_line(&self) -> Option<String> {
        (self.session.count > 0).then(|| {
            let (figures, period) = (self.session.summary(), self.period_words());
            format!("{GPU_TIME}the session: {figures}{period}")
        })
    }

    /// The session's figures so far, as `scripts/bench-xr` gives them (`layer_gpu_ms`):
    /// median, p95 and largest in ms, and the frames measured; and the app's frame period
    /// (median, ms; null before display times came). None before any frame was measured.
    pub fn session_json(&self) -> Option<serde_json::Value> {
        let h = &self.session;
        let ms = |t: Duration| (t.as_secs_f64() * 1e6).round() / 1e3;
        (h.count > 0).then(|| {
            serde_json::json!({
                "median": ms(h.quantile(0.5)),
                "p95": ms(h.quantile(0.95)),
                "largest": ms(h.largest),
                "frames": h.count,
                "frame_period": (self.frame_period.count > 0)
                    .then(|| ms(self.frame_period.quantile(0.5))),
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn us(n: u64) -> Duration {
        Duration::from_micros(n)
    }

    /// Quantiles within the bins' half width of the exact order statistics.
    #[test]
    fn quantiles_are_read_within_half_a_percent() {
        let mut h = Histogram::new();
        // 1000 frames of 100, 101, ... 1099 us: median 599 us (rank 500), p95 1049 us (950).
        for k in 0..1000 {
            h.add(us(100 + k));
        }
        let near = |got: Duration, want: f64| {
            let got = got.as_secs_f64() * 1e6;
            assert!((got / want - 1.0).abs() <= 0.006, "{got} us, not {want} us");
        };
        near(h.quantile(0.5), 599.0);
        near(h.quantile(0.95), 1049.0);
        assert_eq!(h.largest, us(1099));
        near(h.quantile(1.0), 1099.0);
        assert!(h.quantile(1.0) <= us(1099), "never above the largest");
        // Out of the bins' range on both sides: kept, counted.
        h.add(Duration::from_nanos(10));
        h.add(Duration::from_secs(60));
        assert_eq!(h.count, 1002);
        assert_eq!(h.largest, Duration::from_secs(60));
    }

    #[test]
    fn a_line_each_period_and_one_for_the_session() {
        let mut log = GpuTimeLog::default();
        let t0 = Instant::now();
        assert_eq!(log.session_line(), None, "nothing measured");
        assert_eq!(log.session_json(), None);
        assert_eq!(log.add(&[], t0), None);
        assert_eq!(log.add(&[us(400), us(420)], t0), None);
        assert_eq!(log.add(&[us(410)], t0 + Duration::from_secs(30)), None);
        let line = log
            .add(&[us(2000)], t0 + Duration::from_secs(61))
            .expect("a period has passed");
        assert!(line.contains("over the last 61 s"), "{line}");
        assert!(line.contains("largest 2.000 ms, 4 frames"), "{line}");
        assert!(line.contains("median 0.41"), "{line}");
        // The next period starts empty; the session keeps everything.
        let next = log.add(&[us(300)], t0 + Duration::from_secs(122)).unwrap();
        assert!(next.contains("largest 0.300 ms, 1 frame"), "{next}");
        let session = log.session_line().unwrap();
        assert!(session.contains("over the session"), "{session}");
        assert!(session.contains(", 5 frames"), "{session}");
        // The same figures in the capture JSON's form (ms to the microsecond).
        let json = log.session_json().unwrap();
        assert_eq!(json["frames"], 5);
        assert_eq!(json["largest"], 2.0);
        let median = json["median"].as_f64().unwrap();
        assert!((median / 0.41 - 1.0).abs() < 0.006, "{json}");
        assert!(
            session.contains(&format!("median {median:.3} ms")),
            "{session} {json}"
        );
        assert_eq!(
            json["frame_period"],
            serde_json::Value::Null,
            "no display times"
        );
        assert!(session.ends_with(", 5 frames"), "{session}");
    }

    #[test]
    fn the_frame_period_is_the_median_step_of_the_display_times() {
        let mut log = GpuTimeLog::default();
        let ms = 1_000_000i64;
        // 90 Hz (11.111 ms), one frame skipped (a 22.2 ms step), a clock gone back and a
        // pause of 5 s: neither of the last two counts.
        let mut t = 1_000 * ms;
        for k in 0..20 {
            log.display_time(t);
            t += if k == 7 { 22_222_222 } else { 11_111_111 };
        }
        log.display_time(t - 50 * ms);
        log.display_time(t + 5_000 * ms);
        log.display_time(t + 5_000 * ms + 11_111_111);
        assert_eq!(
            log.frame_period.count, 20,
            "19 steps of the first run, 1 after the pause"
        );
        log.add(&[us(500)], Instant::now());
        let line = log.session_line().unwrap();
        assert!(line.ends_with(", 1 frame (frame period 11.1 ms)"), "{line}");
        let period = log.session_json().unwrap()["frame_period"]
            .as_f64()
            .unwrap();
        assert!((period / 11.111 - 1.0).abs() < 0.006, "{period}");
    }
}
