//! CLOCK_MONOTONIC nanoseconds for `Instant`s: the clock V4L2 stamps buffers with and OpenXR's
//! XR_KHR_convert_timespec_time converts from. (`Instant` is CLOCK_MONOTONIC on Linux, but
//! keeps its value private.)

use std::time::{Duration, Instant};

/// CLOCK_MONOTONIC now, nanoseconds.
pub fn monotonic_now_ns() -> i64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec and CLOCK_MONOTONIC always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    #[allow(clippy::unnecessary_cast)] // time_t and c_long are 32 bits on some targets
    let ns = ts.tv_sec as i64 * 1_000_000_000 + ts.tv_nsec as i64;
    ns
}

/// `t` as CLOCK_MONOTONIC nanoseconds.
pub fn monotonic_ns(t: Instant) -> i64 {
    let (now, mono) = (Instant::now(), monotonic_now_ns());
    match now.checked_duration_since(t) {
        Some(age) => mono - age.as_nanos() as i64,
        None => mono + t.duration_since(now).as_nanos() as i64,
    }
}

/// The `Instant` of CLOCK_MONOTONIC nanoseconds `ns`.
pub fn instant_of_ns(ns: i64) -> Instant {
    let (now, mono) = (Instant::now(), monotonic_now_ns());
    let delta = mono - ns;
    if delta >= 0 {
        now.checked_sub(Duration::from_nanos(delta as u64))
            .unwrap_or(now)
    } else {
        now + Duration::from_nanos(delta.unsigned_abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instants_round_trip_through_the_monotonic_clock() {
        let t = Instant::now() - Duration::from_millis(250);
        let ns = monotonic_ns(t);
        let age = monotonic_now_ns() - ns;
        assert!((250_000_000..350_000_000).contains(&age), "{age}");
        let back = instant_of_ns(ns);
        let off = back.max(t) - back.min(t);
        assert!(off < Duration::from_millis(5), "{off:?}");
    }
}
