//! When the layer stops waiting for a program build on a thread of its own. The thread runs
//! below the app's priority, so on a CPU busy with other work it is slow, not stuck, and is
//! waited for; a stuck one (no CPU time at all for a while: a driver waiting forever) or a
//! runaway one (more CPU time than any build needs) is given up, its programs left to the frame
//! calls. Judged by the thread's own CPU clock, which the other threads of the process can read.

use std::os::unix::thread::JoinHandleExt;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a build may go without any CPU time (llvmpipe's whole build is 2-3 s of it).
const QUIET_LIMIT: Duration = Duration::from_secs(60);

/// The CPU time a build may use.
const CPU_LIMIT: Duration = Duration::from_secs(60);

/// How long the layer waits for a build in all (the build's own limit too), and for one whose
/// CPU time cannot be read.
pub const LIMIT: Duration = Duration::from_secs(600);
const UNWATCHED_LIMIT: Duration = Duration::from_secs(60);

/// A build's thread as the layer last saw it.
pub struct BuildWatch {
    pub since: Instant,
    /// The thread's CPU time at its last increase, and when that was seen.
    cpu: Duration,
    busy_at: Instant,
}

impl BuildWatch {
    pub fn new(since: Instant) -> BuildWatch {
        BuildWatch {
            since,
            cpu: Duration::ZERO,
            busy_at: since,
        }
    }

    /// Why the layer gives up on `thread` (not ended) now, if it does.
    pub fn overdue<T>(&mut self, thread: &JoinHandle<T>) -> Option<String> {
        self.overdue_at(Instant::now(), cpu_time(thread))
    }

    /// As `overdue`, at `now`, with the thread's CPU time `cpu` (None: unreadable).
    fn overdue_at(&mut self, now: Instant, cpu: Option<Duration>) -> Option<String> {
        let ran = now.saturating_duration_since(self.since);
        let Some(cpu) = cpu else {
            return (ran > UNWATCHED_LIMIT)
                .then(|| format!("it ran past {} s", UNWATCHED_LIMIT.as_secs()));
        };
        if cpu > self.cpu {
            (self.cpu, self.busy_at) = (cpu, now);
        }
        if cpu > CPU_LIMIT {
            return Some(format!("it used {} s of CPU time", CPU_LIMIT.as_secs()));
        }
        if now.saturating_duration_since(self.busy_at) > QUIET_LIMIT {
            return Some(format!(
                "it got no CPU time for {} s",
                QUIET_LIMIT.as_secs()
            ));
        }
        (ran > LIMIT).then(|| format!("it ran past {} s", LIMIT.as_secs()))
    }
}

/// The CPU time `thread` (running: not joined) has used, where the system tells it.
fn cpu_time<T>(thread: &JoinHandle<T>) -> Option<Duration> {
    let mut clock: libc::clockid_t = 0;
    // SAFETY: a thread not yet joined is a valid pthread_t; the call only writes `clock`.
    if unsafe { libc::pthread_getcpuclockid(thread.as_pthread_t(), &mut clock) } != 0 {
        return None;
    }
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: reads a clock into `now`; a clock of a thread that just ended fails (-1).
    if unsafe { libc::clock_gettime(clock, &mut now) } != 0 {
        return None;
    }
    let nanos = u32::try_from(now.tv_nsec).ok()?;
    Some(Duration::new(u64::try_from(now.tv_sec).ok()?, nanos))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    /// A starved build (50 ms of CPU a second, as on a loaded machine) is waited for up to
    /// LIMIT; one that gets no CPU time for a minute, or uses a minute of it, is given up.
    #[test]
    fn a_slow_build_is_waited_for_and_a_stuck_or_runaway_one_is_not() {
        let start = Instant::now();
        let at = |s: u64| start + Duration::from_secs(s);
        let mut starved = BuildWatch::new(start);
        for s in 1..=599 {
            let cpu = Duration::from_millis(50 * s);
            assert_eq!(starved.overdue_at(at(s), Some(cpu)), None, "at {s} s");
        }
        let ended = starved.overdue_at(at(601), Some(Duration::from_secs(31)));
        assert!(ended.unwrap().contains("ran past 600 s"));

        let mut stuck = BuildWatch::new(start);
        assert_eq!(stuck.overdue_at(at(10), Some(Duration::from_secs(1))), None);
        assert_eq!(stuck.overdue_at(at(70), Some(Duration::from_secs(1))), None);
        let ended = stuck.overdue_at(at(71), Some(Duration::from_secs(1)));
        assert!(ended.unwrap().contains("no CPU time for 60 s"));

        let mut runaway = BuildWatch::new(start);
        let ended = runaway.overdue_at(at(61), Some(Duration::from_secs(61)));
        assert!(ended.unwrap().contains("60 s of CPU time"));

        let mut unwatched = BuildWatch::new(start);
        assert_eq!(unwatched.overdue_at(at(59), None), None);
        assert!(unwatched.overdue_at(at(61), None).unwrap().contains("60 s"));
    }

    /// The clock read is the thread's own: a spinning thread's grows, a sleeping one's does not.
    #[test]
    fn a_threads_cpu_time_is_its_own() {
        let stop = Arc::new(AtomicBool::new(false));
        let spin = {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || while !stop.load(Ordering::Relaxed) {})
        };
        let sleep = std::thread::spawn(|| std::thread::sleep(Duration::from_millis(400)));
        std::thread::sleep(Duration::from_millis(300));
        let spun = cpu_time(&spin).expect("the spinning thread's clock");
        let slept = cpu_time(&sleep).expect("the sleeping thread's clock");
        stop.store(true, Ordering::Relaxed);
        spin.join().unwrap();
        sleep.join().unwrap();
        assert!(spun > Duration::from_millis(20), "{spun:?} spinning");
        assert!(slept < Duration::from_millis(20), "{slept:?} asleep");
    }
}
