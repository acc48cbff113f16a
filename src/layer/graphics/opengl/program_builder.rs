//! The OpenGL programs built off the app's threads, for a driver that compiles inside the GL
//! calls (Mesa's llvmpipe, which offers GL_KHR_parallel_shader_compile but compiles in
//! glLinkProgram, and a driver without parallel compilation): a thread of the layer's own, at a
//! low priority, makes an OpenGL context of its own on EGL's surfaceless platform (never shared
//! with, nor current on, any of the app's contexts), checks that it runs on the app's driver
//! (vendor, renderer and version; a profile does not matter), builds the programs, runs them
//! once so that the driver's shader cache holds their machine code, and writes the program
//! binary cache; the thread hands their binaries back with its end, so that the app's context
//! links them (glProgramBinary) in milliseconds in a frame call without reading the cache's
//! file there. No process is started from the app: a child would stay
//! inside Steam's container or a Flatpak sandbox, with their libraries, and a setuid host would
//! run a file found beside a library. A build cannot be stopped midway: a session that ends
//! first leaves the thread to end on its own, and the process's exit waits for it
//! (gpu/core/process_exit.rs).

use super::build_settle;
use super::build_watch::{BuildWatch, LIMIT};
use crate::algorithm::params::Params;
use crate::gpu::core::process_exit;
use crate::gpu::opengl::device::caps::same_driver;
use crate::gpu::opengl::{GlOffline, ProgramBinaries};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The nice value added to a build thread the app's frames do not wait for: below the app's
/// threads and its driver's.
const BUILD_NICENESS: i32 = 10;

/// A build thread's priority.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum BuildPriority {
    /// Below the app's threads (`BUILD_NICENESS`): its frames pass through meanwhile.
    BelowTheApp,
    /// The app's (`pipelines = "wait"`): its first frame waits for the build, so a lower
    /// priority would only hold the app back longer on a busy CPU.
    App,
}

impl BuildPriority {
    /// Gives the calling thread (a build thread, which started at the app's thread's nice
    /// value) this priority.
    fn enter(self) {
        if self == BuildPriority::BelowTheApp {
            crate::camera::priority::lower_this_thread(BUILD_NICENESS);
        }
    }
}

/// A build of the programs of one view shape.
pub struct ProgramBuilder {
    thread: Option<JoinHandle<Result<ProgramBinaries, String>>>,
    watch: BuildWatch,
    pub shape: (u32, u32, Params),
    /// The programs it builds (the engine's ids), so that a shape needing the same ones does
    /// not start another build.
    pub ids: [usize; 3],
}

/// Where a build stands.
pub enum Built {
    Running,
    /// Ended: Ok with the time it took and the programs' binaries, or why it did not build.
    Ended(Result<(Duration, ProgramBinaries), String>),
}

impl ProgramBuilder {
    /// Starts building the programs `ids` that views of `internal_format`, `width` texels
    /// wide, need for `params` (stored `in_place` or not), on a thread of the layer's own at
    /// `priority`, for the app's `driver`.
    pub fn start(
        driver: &str,
        (internal_format, width, in_place): (u32, u32, bool),
        params: &Params,
        ids: [usize; 3],
        priority: BuildPriority,
    ) -> Result<ProgramBuilder, String> {
        if crate::fault::hit("gl-program-thread") {
            return Err("the build thread could not start (fault point)".into());
        }
        let (driver, wanted) = (driver.to_string(), params.clone());
        process_exit::watch();
        let thread = std::thread::Builder::new()
            .name("contrastxr-gl-build".into())
            .spawn(move || {
                priority.enter();
                build(&driver, (internal_format, width, in_place), &wanted, ids)
            })
            .map_err(|e| format!("no build thread: {e}"))?;
        Ok(ProgramBuilder {
            thread: Some(thread),
            watch: BuildWatch::new(Instant::now()),
            shape: (internal_format, width, params.clone()),
            ids,
        })
    }

    /// Whether the build ended, without waiting; one the layer gives up on (build_watch.rs)
    /// is left to end on its own.
    pub fn poll(&mut self) -> Built {
        let Some(thread) = self.thread.as_ref() else {
            return Built::Ended(Err("already ended".into()));
        };
        if !thread.is_finished() {
            let Some(why) = self.watch.overdue(thread) else {
                return Built::Running;
            };
            self.thread = None;
            return Built::Ended(Err(why));
        }
        let thread = self.thread.take().expect("checked above");
        // The thread has ended: joining it does not wait.
        Built::Ended(match thread.join() {
            Ok(Ok(binaries)) => Ok((self.watch.since.elapsed(), binaries)),
            Ok(Err(why)) => Err(why),
            Err(_) => Err("the build thread panicked".into()),
        })
    }
}

/// The build, on its own thread: an offline context, the driver checked, the programs built
/// and run once, the binaries written; the binaries of `ids`. It ends once their machine code
/// is where the app's context finds it (build_settle.rs): the frame call that links them then
/// does not compile them again.
fn build(
    driver: &str,
    (internal_format, width, in_place): (u32, u32, bool),
    params: &Params,
    ids: [usize; 3],
) -> Result<ProgramBinaries, String> {
    let since = Instant::now();
    // Counted until the offline context is gone (dropped before `_busy`).
    let Some(_busy) = process_exit::Busy::begin() else {
        return Err("the app is exiting".into());
    };
    if crate::fault::hit("gl-program-build") {
        return Err("the build failed (fault point)".into());
    }
    let mut gl = GlOffline::new().map_err(|e| e.to_string())?;
    let own = gl.engine().caps().driver.clone();
    if !same_driver(&own, driver) {
        return Err(format!("another driver here: {own}"));
    }
    gl.engine().set_in_place(in_place);
    // SAFETY: the offline context is current on this thread (GlOffline's contract), and is
    // the only context this thread ever makes current.
    let built = unsafe { gl.engine().warm_up(internal_format, width, params, LIMIT) }
        .map_err(|e| e.to_string())?;
    if !built {
        return Err(match process_exit::exiting() {
            true => "the app is exiting".into(),
            false => format!("not built within {} s", LIMIT.as_secs()),
        });
    }
    gl.engine().save_program_cache();
    let binaries = gl.engine().program_binaries(&ids);
    drop(gl);
    let shape = (internal_format, width, in_place);
    build_settle::settle(&binaries, shape, params, since.elapsed());
    Ok(binaries)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nice value of the calling thread.
    fn own_nice() -> i32 {
        // SAFETY: getpriority of this thread's own id only reads it.
        unsafe { libc::getpriority(libc::PRIO_PROCESS, libc::gettid() as libc::id_t) }
    }

    /// The nice value a new thread has after entering `priority`, and the spawning thread's.
    fn nice_in(priority: BuildPriority) -> (i32, i32) {
        let app = own_nice();
        let build = std::thread::spawn(move || {
            priority.enter();
            own_nice()
        });
        (build.join().unwrap(), app)
    }

    #[test]
    fn a_build_the_frames_wait_for_runs_at_the_apps_priority_and_others_below_it() {
        let (build, app) = nice_in(BuildPriority::App);
        assert_eq!(build, app);
        let (build, app) = nice_in(BuildPriority::BelowTheApp);
        assert_eq!(build, (app + BUILD_NICENESS).min(19));
    }
}
