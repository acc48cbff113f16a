//! The end of a build off the app's threads. A driver that compiles a program's machine code
//! at its first dispatch keeps that code in a disk cache (Mesa's llvmpipe), written by threads
//! of the driver's own at the lowest priority (Mesa: nice 19, SCHED_BATCH). On a CPU busy with
//! other work they lag behind the build, and the app's context, linking the build's binaries in
//! a frame call, would compile the whole set again there: a frame call of many seconds. So
//! before the build hands its binaries back, its thread waits for those writers to go idle,
//! then links the binaries in a second context of its own and runs them once, as the app's
//! context will; a run about as slow as a compile while the writers were still busy (its wait
//! for them ran out) means the code was not on disk yet, and it waits and checks again, a few
//! times at most.

use crate::algorithm::params::Params;
use crate::gpu::core::process_exit;
use crate::gpu::opengl::{GlOffline, ProgramBinaries};
use crate::layer::log;
use std::time::{Duration, Instant};

/// Checks at most: each that misses the disk cache costs a compile on the build thread.
const CHECKS: usize = 3;

/// How long one wait for the cache writers lasts at most.
const WRITERS_LIMIT: Duration = Duration::from_secs(30);

/// How often the writers' states are read while waiting.
const WRITERS_POLL: Duration = Duration::from_millis(20);

/// A check's run this short found the machine code, however short the build was.
const FAST: Duration = Duration::from_millis(100);

/// A check's run found the machine code when it took at most this fraction of the build
/// (a compile again takes most of it).
const FAST_FRACTION: u32 = 4;

/// The last check of a build's end.
#[derive(Debug)]
pub struct Settled {
    /// Which check it was (from 1).
    pub check: usize,
    /// How long linking the binaries and running them once took in it.
    pub ran: Duration,
    /// Whether the driver's cache writers were idle before it.
    pub writers_idle: bool,
}

/// Waits until linking `binaries` and running them once in a new context of this driver is
/// fast (`built_in`: how long the build took), or slow with the writers idle before it, or the
/// checks run out; None when no check ran (no writer threads, the driver refused a binary,
/// the app began to exit, or no context). Views of
/// `internal_format`, `width` texels wide, stored `in_place` or not, for `params`.
pub fn settle(
    binaries: &ProgramBinaries,
    (internal_format, width, in_place): (u32, u32, bool),
    params: &Params,
    built_in: Duration,
) -> Option<Settled> {
    // No writers: the driver keeps no disk cache (or is not Mesa), and the app's context
    // compiles whatever it lacks however long this thread waits.
    if writer_states().is_empty() {
        return None;
    }
    let since = Instant::now();
    for check in 1..=CHECKS {
        let writers_idle = wait_for_writers(WRITERS_LIMIT);
        if process_exit::exiting() {
            return None;
        }
        // None: not linked from the binaries (the driver refused them) or not run: nothing
        // the app's context would find faster by waiting.
        let ran = relinked_run(binaries, (internal_format, width, in_place), params)
            .map_err(|why| {
                log::debug(&format!(
                    "OpenGL programs' check in a second context: {why}"
                ))
            })
            .ok()??;
        // Slow although the writers had gone idle: the code is not coming (a cache full or
        // keyed apart); another check would only compile it again.
        if is_fast(ran, built_in) || writers_idle || check == CHECKS {
            let settled = Settled {
                check,
                ran,
                writers_idle,
            };
            log::debug(&format!(
                "OpenGL programs linked and run once in a second context in {:.3} s (check {}, {:.3} s after the build; the driver's cache writers {})",
                settled.ran.as_secs_f64(),
                settled.check,
                since.elapsed().as_secs_f64(),
                if settled.writers_idle { "idle" } else { "still busy" }
            ));
            return Some(settled);
        }
    }
    None
}

/// Whether a check's run of `ran` found the machine code of a build that took `built_in`.
fn is_fast(ran: Duration, built_in: Duration) -> bool {
    ran <= FAST || ran * FAST_FRACTION <= built_in
}

/// The binaries linked in a new context and run once: the time both took, None when the
/// driver refused a binary or the app began to exit.
fn relinked_run(
    binaries: &ProgramBinaries,
    (internal_format, width, in_place): (u32, u32, bool),
    params: &Params,
) -> Result<Option<Duration>, String> {
    let mut gl = GlOffline::new().map_err(|e| e.to_string())?;
    let engine = gl.engine();
    engine.set_in_place(in_place);
    engine.take_program_binaries(binaries.clone());
    let since = Instant::now();
    // SAFETY: the offline context is current on this thread (GlOffline's contract).
    let linked = unsafe { engine.ready_from_cache(internal_format, width, params) };
    if !linked.map_err(|e| e.to_string())? {
        return Ok(None);
    }
    // SAFETY: as above.
    let ran = unsafe { engine.warm_up(internal_format, width, params, WRITERS_LIMIT) };
    Ok(ran.map_err(|e| e.to_string())?.then(|| since.elapsed()))
}

/// Waits until every disk cache writer thread of the driver in this process sleeps, seen
/// twice in a row, or `limit` passed (false), or the app began to exit.
fn wait_for_writers(limit: Duration) -> bool {
    let since = Instant::now();
    let mut idle_before = false;
    while since.elapsed() < limit && !process_exit::exiting() {
        let idle = writer_states().iter().all(|&s| s == 'S');
        if idle && idle_before {
            return true;
        }
        idle_before = idle;
        std::thread::sleep(WRITERS_POLL);
    }
    false
}

/// The scheduler states (`R` running, `S` sleeping, `D` in I/O, ...) of this process's
/// threads that write a Mesa driver's shader disk cache: Mesa names them `disk$N`, after the
/// process's name.
fn writer_states() -> Vec<char> {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return Vec::new();
    };
    let states = tasks.flatten().filter_map(|task| {
        let stat = std::fs::read_to_string(task.path().join("stat")).ok()?;
        thread_state(&stat, "disk$")
    });
    states.collect()
}

/// The state in a thread's `/proc/.../stat` line when its name holds `name`: the name sits
/// in parentheses and may hold spaces and parentheses itself, so the state is read after the
/// last `)`.
fn thread_state(stat: &str, name: &str) -> Option<char> {
    let (open, close) = (stat.find('(')?, stat.rfind(')')?);
    if !stat.get(open + 1..close)?.contains(name) {
        return None;
    }
    stat[close + 1..].trim_start().chars().next()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_threads_state_is_read_after_the_last_parenthesis_of_its_name() {
        let stat = "4242 (app:disk$0) S 1 2 3";
        assert_eq!(thread_state(stat, "disk$"), Some('S'));
        let odd = "4243 (a) (disk$1)) R 1 2 3";
        assert_eq!(thread_state(odd, "disk$"), Some('R'));
        assert_eq!(thread_state("4244 (llvmpipe-0) R 1", "disk$"), None);
        assert_eq!(thread_state("garbage", "disk$"), None);
    }

    #[test]
    fn a_run_far_shorter_than_the_build_found_the_machine_code() {
        let s = Duration::from_secs_f64;
        assert!(is_fast(s(0.03), s(3.0)));
        assert!(is_fast(s(0.09), s(0.1)));
        assert!(is_fast(s(1.0), s(24.0)));
        assert!(!is_fast(s(18.0), s(24.0)));
        assert!(!is_fast(s(0.5), s(1.0)));
    }

    /// A real build's end on this machine's driver: Mesa's writer threads are found by their
    /// name (were they renamed, the wait would not see them), go idle, and a check links the
    /// binaries and runs them (how fast is the driver's and the machine's load's).
    #[test]
    fn a_builds_end_finds_the_drivers_cache_writers_and_checks_its_binaries() {
        let params = Params::default();
        let (format, width) = (crate::gpu::opengl::device::functions::RGBA8, 16);
        let mut gl = GlOffline::new().expect("an OpenGL context");
        let since = Instant::now();
        // SAFETY: the offline context is current on this thread.
        let built = unsafe { gl.engine().warm_up(format, width, &params, WRITERS_LIMIT) };
        assert!(built.expect("built"));
        let built_in = since.elapsed();
        let ids = gl
            .engine()
            .shape_program_ids(format, width, &params)
            .unwrap();
        let binaries = gl.engine().program_binaries(&ids);
        let software = gl.engine().caps().software;
        drop(gl);
        if software {
            assert!(!writer_states().is_empty(), "no disk$ threads of Mesa's");
        }
        let settled = settle(&binaries, (format, width, false), &params, built_in);
        let settled = settled.expect("a check ran");
        assert!((1..=CHECKS).contains(&settled.check));
        // Seen asleep (or none: not Mesa), however long a loaded machine makes them take.
        assert!(wait_for_writers(Duration::from_secs(300)));
    }
}
