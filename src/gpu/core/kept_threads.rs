//! Threads kept between sessions for long jobs of the same kind (the pipeline builds): a job
//! runs on an idle thread of its kind where there is one, else on a new one, which waits for
//! the next job for IDLE_FOR once it is done, then ends (nothing of the layer outlives its
//! instances by more than that: tests/unload.rs). glibc gives each new thread a malloc arena no live thread uses
//! (up to 8 per core) and every arena keeps its high-water mark: a new build thread per session
//! left a driver's compile memory in a new arena each time, up to 16 arenas (about 17 MB each
//! on lavapipe) on a 2-core machine. A kept thread keeps its arena. The library is never
//! unloaded (`RTLD_NODELETE`), so an idle thread waiting here is safe until the process ends.
//! An app that ends a session and starts the next within IDLE_FOR (a restart, a focus change)
//! keeps its build thread.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{channel, Sender};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// How long a thread waits for its next job before it ends.
const IDLE_FOR: Duration = Duration::from_millis(500);

type Job = Box<dyn FnOnce() + Send>;
type Signal = Arc<(Mutex<bool>, Condvar)>;
/// An idle thread: its name, its number and where its next job goes. Whoever takes it out of
/// the list (under the list's lock) owns it: `run` to send it a job, the thread itself to end.
type Idle = (&'static str, u64, Sender<(Job, Signal)>);

fn idle() -> std::sync::MutexGuard<'static, Vec<Idle>> {
    static IDLE: Mutex<Vec<Idle>> = Mutex::new(Vec::new());
    IDLE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Takes the idle thread numbered `number` out of the list; whether it was there.
fn take_out(number: u64) -> bool {
    let mut idle = idle();
    let k = idle.iter().position(|(_, n, _)| *n == number);
    k.map(|k| idle.swap_remove(k)).is_some()
}

/// The end of one job, to wait for.
pub struct JobDone(Signal);

impl JobDone {
    /// Waits until the job has returned (or panicked).
    pub fn join(self) {
        let (done, changed) = &*self.0;
        let mut finished = done.lock().unwrap_or_else(|p| p.into_inner());
        while !*finished {
            finished = changed.wait(finished).unwrap_or_else(|p| p.into_inner());
        }
    }
}

/// Runs `job` on an idle thread named `name`, or on a new one. A panic in the job ends the job,
/// not the thread.
pub fn run(name: &'static str, job: impl FnOnce() + Send + 'static) -> std::io::Result<JobDone> {
    let signal: Signal = Arc::new((Mutex::new(false), Condvar::new()));
    let mut work: (Job, Signal) = (Box::new(job), signal.clone());
    loop {
        let free = {
            let mut idle = idle();
            let k = idle.iter().position(|(n, _, _)| *n == name);
            k.map(|k| idle.swap_remove(k).2)
        };
        let Some(thread) = free else { break };
        match thread.send(work) {
            Ok(()) => return Ok(JobDone(signal)),
            // That thread is gone: the job comes back.
            Err(e) => work = e.0,
        }
    }
    static NUMBERS: AtomicU64 = AtomicU64::new(0);
    let number = NUMBERS.fetch_add(1, Ordering::Relaxed);
    let (tx, rx) = channel::<(Job, Signal)>();
    tx.send(work).expect("the receiver is here");
    std::thread::Builder::new()
        .name(name.into())
        .spawn(move || loop {
            let (job, signal) = match rx.recv_timeout(IDLE_FOR) {
                Ok(work) => work,
                // Still in the list: nobody will send a job; else one is on its way.
                Err(_) if take_out(number) => return,
                Err(_) => match rx.recv() {
                    Ok(work) => work,
                    Err(_) => return,
                },
            };
            let _ = catch_unwind(AssertUnwindSafe(job));
            // Idle again before the job's end is seen, so the next job finds this thread.
            idle().push((name, number, tx.clone()));
            let (finished, changed) = &*signal;
            *finished.lock().unwrap_or_else(|p| p.into_inner()) = true;
            changed.notify_all();
        })?;
    Ok(JobDone(signal))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thread_of_job(name: &'static str) -> std::thread::ThreadId {
        let (tx, rx) = channel();
        run(name, move || tx.send(std::thread::current().id()).unwrap())
            .unwrap()
            .join();
        rx.recv().unwrap()
    }

    /// A job after another of the same kind runs on the same thread; a panic ends the job and
    /// its wait, and the thread takes the next job; a thread idle for longer than IDLE_FOR
    /// ends, and the next job gets a new one.
    #[test]
    fn jobs_of_a_kind_share_a_kept_thread_until_it_idles_out() {
        let first = thread_of_job("contrastxr-test-kept");
        assert_eq!(thread_of_job("contrastxr-test-kept"), first);
        run("contrastxr-test-kept", || panic!("in the job"))
            .unwrap()
            .join();
        assert_eq!(thread_of_job("contrastxr-test-kept"), first);
        assert_ne!(thread_of_job("contrastxr-test-other"), first);
        let kept = || idle().iter().any(|(n, _, _)| *n == "contrastxr-test-kept");
        let deadline = std::time::Instant::now() + IDLE_FOR * 20;
        while kept() && std::time::Instant::now() < deadline {
            std::thread::sleep(IDLE_FOR / 5);
        }
        assert!(!kept(), "still idle after {:?}", IDLE_FOR * 20);
        assert_ne!(thread_of_job("contrastxr-test-kept"), first);
    }
}
